"""The agents x pose sources comparison of ``stsf-gym evaluate``."""

import json

import pytest

from stsf_gym.cli import main
from stsf_gym.experiments.compare import agent_for, compare
from stsf_gym.results import check_rows

SHORT = {"camera": {"enabled": False}, "sim": {"max_episode_seconds": 8.0}}


def test_each_pose_source_gets_its_own_model():
    assert agent_for("runs/ppo-{estimator}/model.zip", "stsf") == "runs/ppo-stsf/model.zip"
    assert agent_for("follower", "stsf") == "follower"


@pytest.mark.slow
def test_comparison_has_a_row_per_pair_and_a_figure(tmp_path):
    summary = compare(tmp_path, ["follower"], ["truth", "odometry"], seeds=2, workers=1, env=SHORT)
    rows = summary["rows"]
    assert [(r["agent"], r["estimator"]) for r in rows] == [
        ("follower", "truth"),
        ("follower", "odometry"),
    ]
    assert all(r["episodes"] == 2 for r in rows)
    assert rows[0]["final_error_m"]["mean"] < 1e-4  # the true pose has no error
    assert rows[1]["final_error_m"]["mean"] > 1e-3  # dead reckoning drifts
    assert (tmp_path / "comparison.png").stat().st_size > 0
    saved = json.loads((tmp_path / "comparison.json").read_text())
    assert [r["estimator"] for r in saved["rows"]] == ["truth", "odometry"]
    check_rows(saved["rows"])
    assert "| ATE RMSE (m) |" in (tmp_path / "comparison.md").read_text()


def test_cli_names_a_missing_model_of_one_pose_source(tmp_path, capsys):
    code = main(
        [
            "evaluate",
            "--agent",
            f"follower,{tmp_path}/ppo-{{estimator}}.zip",
            "--estimators",
            "truth",
            "--out",
            str(tmp_path / "out"),
        ]
    )
    assert code == 2
    assert "ppo-truth.zip" in capsys.readouterr().err
    assert not (tmp_path / "out" / "comparison.json").exists()
