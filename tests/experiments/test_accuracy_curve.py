"""``stsf-gym accuracy-curve`` end to end on a tiny run, its reading, and its errors."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from stsf_gym.experiments.curve.run import accuracy_curve, tolerated_ate
from stsf_gym.experiments.jobs.store import read_rows
from stsf_gym.results import check_rows

TINY = ["--world", "straight_10m", "--seeds", "1", "--levels", "1,30", "--estimators", "odometry"]


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("curve")
    command = [sys.executable, "-m", "stsf_gym.cli", "accuracy-curve", *TINY, "--out", str(out)]
    done = subprocess.run([*command, "--json"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return out, json.loads(done.stdout)


@pytest.mark.slow
def test_curve_files_hold_numbers(tiny_run):
    out, summary = tiny_run
    on_disk = json.loads((out / "curve.json").read_text())
    (curve,) = on_disk["curves"]
    assert curve["agent"] == "follower" and [level["scale"] for level in curve["levels"]] == [1, 30]
    check_rows(curve["levels"], "levels")
    check_rows(on_disk["estimators"], "estimators")
    small, large = curve["levels"]
    assert small["ate_rmse_m"]["count"] == 1
    assert small["ate_rmse_m"]["mean"] < large["ate_rmse_m"]["mean"]  # the dial works
    assert small["path_error_rms_m"]["mean"] < large["path_error_rms_m"]["mean"]
    assert small["success_rate"]["mean"] == 1.0 and large["success_rate"]["mean"] == 0.0
    assert curve["tolerated_ate_m"] == small["ate_rmse_m"]["mean"]
    (odometry,) = on_disk["estimators"]
    assert odometry["estimator"] == "odometry" and odometry["ate_rmse_m"]["mean"] > 0
    assert (out / "curve.png").stat().st_size > 10_000
    assert "reaches the goal in >= 90% of episodes up to ATE" in (out / "curve.md").read_text()
    assert len(read_rows(out / "cells.sqlite")) == 3
    assert summary["curves"] == on_disk["curves"]


@pytest.mark.slow
def test_ray_backend_gives_the_same_curve(tiny_run, tmp_path):
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'stsf-gym[ray]')")
    _, summary = tiny_run
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        on_ray = accuracy_curve(
            tmp_path,
            ["follower"],
            "straight_10m",
            seeds=1,
            levels=[1.0, 30.0],
            estimators=["odometry"],
            backend="ray",
        )
    finally:
        ray.shutdown()
    assert on_ray["curves"] == summary["curves"]
    assert on_ray["estimators"] == summary["estimators"]


def test_tolerated_ate_stops_at_the_first_failing_level():
    def level(scale, success, ate):
        return {"scale": scale, "success_rate": {"mean": success}, "ate_rmse_m": {"mean": ate}}

    levels = [level(2, 0.9, 0.2), level(1, 1.0, 0.1), level(4, 0.5, 0.4), level(8, 1.0, 0.8)]
    assert tolerated_ate(levels) == 0.2  # 8 succeeds again, but 4 failed first
    assert tolerated_ate([level(1, 0.8, 0.1)]) is None


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--dial", "nosie_std=[1, 1]"], "nosie_std"),
        (["--dial", "latency_s=-1"], "latency_s"),
        (["--levels", "1,abc"], "--levels"),
        (["--levels", "0"], "levels"),
        (["--estimators", "magic"], "'magic'"),
        (["--agent", "missing.zip"], "missing.zip"),
    ],
)
def test_bad_arguments_are_named_before_any_work(tmp_path, args, message):
    out = tmp_path / "out"
    command = [sys.executable, "-m", "stsf_gym.cli", "accuracy-curve", "--out", str(out), *args]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and message in done.stderr
    assert not out.exists()
