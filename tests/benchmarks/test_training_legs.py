"""benchmarks/training_legs.py: a reward stage's training legs, early against late."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import load_script

from stsf_gym.io import write_json


def _script():
    return load_script("benchmarks/training_legs.py")


def _run(folder: Path, legs: list[tuple[float, int, int]]) -> Path:
    """A run folder: ``train.json`` (150 s legs, a decision every 5 control steps of 0.1 s:
    300 decisions at the limit) and ``episodes.csv`` of ``(return, decisions, success)``."""
    folder.mkdir(parents=True)
    train = {"algo": "ppo", "seed": 3, "decision_steps": 5}
    train["hyperparams"] = {"train_env": {"sim": {"max_episode_seconds": 150.0}}}
    write_json(folder / "train.json", train)
    rows = ["timesteps,reward,length,success,control_steps"]
    rows += [f"{i},{r},{n},{s},{5 * n}" for i, (r, n, s) in enumerate(legs)]
    (folder / "episodes.csv").write_text("\n".join(rows) + "\n")
    return folder


def test_legs_early_and_late_count_declarations_and_time_limits(tmp_path, capsys):
    early = [(-10.0, 2, 0), (-10.0, 4, 0), (3.0, 300, 0)]
    late = [(2.0, 300, 0), (20.0, 300, 1), (4.0, 300, 0)]  # a success on the last decision
    run = _run(tmp_path / "seed-3", early + late)
    legs = _script()
    out = tmp_path / "legs.json"
    legs.main([str(run), "--window", "3", "--out", str(out)])
    measured = json.loads(out.read_text())["runs"][str(run)]
    assert measured["time_limit_decisions"] == 300
    assert measured["all"] | {"return": None} == {
        "legs": 6, "correct_declarations": 1, "time_limit": 3, "median_decisions": 300.0,
        "return": None,
    }  # fmt: skip
    assert (measured["first"]["time_limit"], measured["first"]["median_decisions"]) == (1, 4.0)
    assert measured["first"]["return"]["values"] == [-10.0, -10.0, 3.0]
    assert (measured["last"]["time_limit"], measured["last"]["correct_declarations"]) == (2, 1)
    assert "| 1 / 4 / -5.7 | 2 / 300 / +8.7 |" in capsys.readouterr().out


def test_a_folder_without_a_finished_run_is_refused_by_name(tmp_path, capsys):
    with pytest.raises(SystemExit):
        _script().main([str(tmp_path)])
    assert f"{tmp_path}: no train.json" in capsys.readouterr().err
