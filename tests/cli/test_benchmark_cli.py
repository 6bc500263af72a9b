"""``stsf-gym benchmark --suite`` and ``accuracy-curve --suite`` end to end on tiny runs."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from stsf_gym.experiments.jobs.store import read_rows
from stsf_gym.results import check_rows

TINY = ["--suite", "corridor", "--worlds", "2", "--estimators", "truth,odometry"]


def cli(*args: str) -> dict:
    command = [sys.executable, "-m", "stsf_gym.cli", *args, "--json"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def tiny_benchmark(tmp_path_factory):
    out = tmp_path_factory.mktemp("benchmark")
    return out / "corridor", cli("benchmark", *TINY, "--out", str(out))


@pytest.mark.slow
def test_benchmark_writes_the_leaderboard(tiny_benchmark):
    out, summary = tiny_benchmark
    on_disk = json.loads((out / "results.json").read_text())
    assert on_disk["protocol"] == "declare" and on_disk["goal_radius_m"] == 0.25
    check_rows(on_disk["rows"])
    rows = {row["estimator"]: row for row in on_disk["rows"]}
    assert set(rows) == {"truth", "odometry"}
    for row in rows.values():
        assert row["episodes"] == 2 and row["seeds"] == [0, 1]
        assert len(row["spl"]["values"]) == 2 and len(row["success_rate"]["values"]) == 2
        low, high = row["success_ci95"]
        assert 0 <= low <= row["success_rate"]["mean"] <= high <= 1
        assert all(0 <= v <= 1 for v in row["spl"]["values"])
        assert len(row["stop_distance_m"]["values"]) >= 1  # a declared stop at least
    assert rows["truth"]["stop_distance_m"]["values"][0] < 0.25  # the truth stops on the goal
    (pair,) = on_disk["paired"]
    assert {pair["first"], pair["second"]} == {"truth", "odometry"}
    assert pair["success_difference"]["pairs"] == 2
    assert on_disk["worlds"]["coverage"]["values"] == [1.0, 1.0]  # today's density
    near = {row["estimator"]: row for row in on_disk["behaviour"]}  # read from the same cells
    for source, row in rows.items():
        assert near[source]["episodes"] == 2
        assert near[source]["stop_distance_m"]["values"] == row["stop_distance_m"]["values"]
        assert near[source]["success"]["mean"] == row["success_rate"]["mean"]
    assert max(near["truth"]["stop_sigma_m"]["values"]) < 0.01  # the true pose's tiny sigma
    assert (out / "leaderboard.png").stat().st_size > 10_000
    assert "| follower | truth |" in (out / "leaderboard.md").read_text()
    assert summary["rows"] == on_disk["rows"]


def test_benchmark_resumes(tiny_benchmark, tmp_path):
    out, summary = tiny_benchmark
    stamps = {key: row.written_ns for key, row in read_rows(out / "cells.sqlite").items()}
    assert len(stamps) == 4
    again = cli("benchmark", *TINY, "--out", str(out.parent))
    assert {k: row.written_ns for k, row in read_rows(out / "cells.sqlite").items()} == stamps
    assert again["rows"] == summary["rows"]


def test_bad_benchmark_input_is_named(tmp_path):
    command = [sys.executable, "-m", "stsf_gym.cli", "benchmark", "--out", str(tmp_path)]
    done = subprocess.run([*command, "--suite", "hardest"], capture_output=True, text=True)
    assert done.returncode == 2 and "invalid choice: 'hardest'" in done.stderr
    bad = [*command, "--suite", "corridor", "--estimators", "gps"]
    done = subprocess.run(bad, capture_output=True, text=True)
    assert done.returncode == 2 and "unknown estimator 'gps'" in done.stderr


@pytest.mark.slow
def test_accuracy_curve_on_the_declared_stop_task(tmp_path):
    args = ["--suite", "corridor", "--seeds", "1", "--levels", "1", "--estimators", ""]
    summary = cli("accuracy-curve", *args, "--out", str(tmp_path))
    on_disk = json.loads((tmp_path / "curve.json").read_text())
    assert on_disk["protocol"] == "declare" and on_disk["goal_radius_m"] == 0.25
    assert on_disk["suite"] == "corridor" and on_disk["world"] == "generated:test"
    (curve,) = on_disk["curves"]
    assert "tolerated_ate_m" in curve and len(curve["levels"]) == 1
    assert "Declared arrival" in (tmp_path / "curve.md").read_text()
    assert summary["curves"] == on_disk["curves"]
