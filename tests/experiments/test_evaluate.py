import json
import subprocess
import sys

import pytest

import stsf_gym.experiments.episodes as episodes
from stsf_gym.experiments.evaluate import evaluate
from stsf_gym.experiments.jobs.store import read_rows
from stsf_gym.results import SCHEMA_VERSION, check_rows
from stsf_gym.results.schema import NEES_VERDICTS

FAST = {"camera": {"enabled": False}, "sim": {"max_episode_seconds": 4.0}}


@pytest.mark.slow
def test_evaluate_writes_table_figures_and_resumes(tmp_path, monkeypatch):
    summary, _ = evaluate(
        tmp_path, ["odometry"], seeds=2, world="straight_10m", workers=1, env=FAST
    )
    row = summary["rows"][0]
    assert row["estimator"] == "odometry" and row["episodes"] == 2
    assert row["success_rate"] == {"mean": 0.0, "std": 0.0, "count": 2, "values": [0.0, 0.0]}
    for name in ("results.json", "results.md", "trajectories.png", "errors.png", "nees.png"):
        assert (tmp_path / name).stat().st_size > 0
    for seed in (0, 1):  # every step of each episode, as TUM files
        folder = tmp_path / "episodes" / "trajectories" / f"straight_10m-odometry-follower-{seed}"
        lines = (folder / "estimate.txt").read_text().splitlines()
        assert len(lines) == 1 + 41 and len(lines[1].split()) == 8  # header, t = 0 and 40 steps
        assert (folder / "truth.txt").read_text().splitlines()[-1].startswith("4.0")
    store = tmp_path / "episodes" / "episodes.sqlite"
    stamps = {key: row.written_ns for key, row in read_rows(store).items()}
    assert len(stamps) == 2  # one row per episode

    def interrupted(job):
        raise KeyboardInterrupt

    monkeypatch.setattr(episodes, "run_episode", interrupted)
    again, _ = evaluate(tmp_path, ["odometry"], seeds=2, world="straight_10m", workers=1, env=FAST)
    assert again["rows"] == summary["rows"]  # nothing rerun: both episodes were kept
    assert {key: row.written_ns for key, row in read_rows(store).items()} == stamps
    with pytest.raises(KeyboardInterrupt):  # a third seed is new work: it runs (and stops)
        evaluate(tmp_path, ["odometry"], seeds=3, world="straight_10m", workers=1, env=FAST)
    assert len(read_rows(store)) == 2  # earlier results intact


@pytest.mark.slow
def test_evaluate_cli_json_schema(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "stsf_gym.cli",
            "evaluate",
            "--json",
            "--out",
            str(tmp_path),
            "--estimators",
            "odometry,ekf",
            "--world",
            "straight_10m",
            "--seeds",
            "1",
            "--workers",
            "1",
            "--set",
            "sim.max_episode_seconds=3",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)
    assert set(summary) >= {"world", "agent", "seeds", "rows", "figures"}
    assert [row["estimator"] for row in summary["rows"]] == ["odometry", "ekf"]
    assert summary["schema_version"] == SCHEMA_VERSION
    assert set(summary["rows"][0]) >= {
        "agent",
        "estimator",
        "success_rate",
        "collision_rate",
        "ate_rmse_m",
        "rpe_trans_m_per_m",
        "rpe_rot_deg_per_m",
        "final_error_m",
        "nees_mean",
        "nees_bounds",
        "nees_in_bounds",
        "nees_time_average",
        "nees_time_bounds",
        "nees_effective_steps",
        "nees_verdict",
        "nis_mean",
        "nis_bounds",
        "match_rate",
        "ms_per_step",
    }
    check_rows(summary["rows"])
    for row in summary["rows"]:  # the time average's own bounds lie within the per-step ones
        low, high = row["nees_time_bounds"]
        assert row["nees_bounds"][0] <= low < 3 < high <= row["nees_bounds"][1]
    ekf = summary["rows"][1]
    assert ekf["nis_mean"]["count"] == 1 and ekf["nis_bounds"][0] < 2 < ekf["nis_bounds"][1]
    assert summary["rows"][0]["nis_mean"] == {
        "mean": None,
        "std": None,
        "count": 0,
        "values": [None],
    }
    assert isinstance(ekf["ms_per_step"]["update"]["mean"], float)
    for row in summary["rows"]:  # 3 s: cut at the time limit, neither reached nor failed
        assert row["time_limit_rate"]["mean"] == 1.0 and row["collision_rate"]["mean"] == 0.0
    table = (tmp_path / "results.md").read_text()
    assert "| time limit rate | distance before failure or time limit (m) |" in table
    verdicts = [NEES_VERDICTS[row["nees_verdict"]] for row in summary["rows"]]
    assert all(f"| {verdict} |" in table for verdict in verdicts)  # words, not -1/0/1


@pytest.mark.slow
def test_unknown_estimator_rejected(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "stsf_gym.cli",
            "evaluate",
            "--out",
            str(tmp_path),
            "--estimators",
            "odometry,magic",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2 and "'magic'" in result.stderr


@pytest.mark.slow
def test_evaluate_on_ray_gives_the_local_rows(tmp_path):
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'stsf-gym[ray]')")
    args = (["odometry"],)
    kwargs = {"seeds": 2, "world": "straight_10m", "workers": 1, "env": FAST}
    local, _ = evaluate(tmp_path / "local", *args, **kwargs)
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        on_ray, _ = evaluate(tmp_path / "ray", *args, **kwargs, backend="ray")
    finally:
        ray.shutdown()

    def untimed(rows):  # wall-clock timings differ from run to run
        return [{k: v for k, v in row.items() if k != "ms_per_step"} for row in rows]

    assert untimed(on_ray["rows"]) == untimed(local["rows"])
    assert len(read_rows(tmp_path / "ray" / "episodes" / "episodes.sqlite")) == 2
