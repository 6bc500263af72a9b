import json
import subprocess
import sys

import pytest

import stsf_gym.experiments.episodes as episodes
from stsf_gym.experiments.evaluate import evaluate

FAST = {"camera": {"enabled": False}, "sim": {"max_episode_seconds": 4.0}}


def test_evaluate_writes_table_figures_and_resumes(tmp_path, monkeypatch):
    summary, _ = evaluate(
        tmp_path, ["odometry"], seeds=2, world="straight_10m", workers=1, env=FAST
    )
    row = summary["rows"][0]
    assert row["estimator"] == "odometry" and row["episodes"] == 2
    assert row["success rate"] == 0.0  # 4 s is far too short for 10 m
    for name in ("results.json", "results.md", "trajectories.png", "errors.png"):
        assert (tmp_path / name).stat().st_size > 0
    files = sorted((tmp_path / "episodes").glob("*.json"))
    assert len(files) == 2
    stamps = [f.stat().st_mtime_ns for f in files]

    def interrupted(job):
        raise KeyboardInterrupt

    monkeypatch.setattr(episodes, "run_episode", interrupted)
    again, _ = evaluate(tmp_path, ["odometry"], seeds=2, world="straight_10m", workers=1, env=FAST)
    assert again["rows"] == summary["rows"]  # nothing rerun: both episodes were kept
    assert [f.stat().st_mtime_ns for f in files] == stamps
    with pytest.raises(KeyboardInterrupt):  # a third seed is new work: it runs (and stops)
        evaluate(tmp_path, ["odometry"], seeds=3, world="straight_10m", workers=1, env=FAST)
    assert len(list((tmp_path / "episodes").glob("*.json"))) == 2  # earlier results intact


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
    assert set(summary["rows"][0]) >= {
        "success rate",
        "final error (m)",
        "NEES",
        "NEES 95% bounds",
        "landmark match rate",
        "ms per step",
    }


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
