"""benchmarks/studies/declaration_pilot.py: a unit's bookkeeping (resume, extend, set aside)
and its leg summaries, without training."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import load_script

from stsf_gym.io import write_json


@pytest.fixture(scope="module")
def pilot():
    return load_script("benchmarks/studies/declaration_pilot.py")


SETTINGS = {"suite": "corridor", "decisions": 100, "eval_every": 50, "seed": 0, "learner": {}}


def _unit(folder: Path, settings: dict, *, result: bool) -> Path:
    """A unit that ran ``settings`` to its end (a result) or to half of it (a state only)."""
    folder.mkdir(parents=True)
    (folder / "model.zip").write_bytes(b"weights")
    (folder / "monitor").mkdir()
    done = settings["decisions"] if result else settings["decisions"] // 2
    write_json(folder / "state.json", {"settings": settings, "decisions": done, "val": []})
    if result:
        write_json(folder / "result.json", {"settings": settings})
    return folder


def test_a_finished_unit_of_the_same_settings_is_skipped(pilot, tmp_path: Path) -> None:
    unit = _unit(tmp_path / "u", SETTINGS, result=True)
    assert pilot.finished(unit, SETTINGS)
    assert (unit / "model.zip").is_file()


@pytest.mark.parametrize("result", [True, False])
def test_a_larger_budget_extends_the_unit(pilot, tmp_path: Path, result: bool) -> None:
    unit = _unit(tmp_path / "u", SETTINGS, result=result)
    longer = {**SETTINGS, "decisions": 400}
    assert not pilot.finished(unit, longer)
    state = json.loads((unit / "state.json").read_text())
    assert state["settings"] == longer
    assert state["decisions"] == (100 if result else 50)  # resumes where it stopped
    assert (unit / "model.zip").is_file() and (unit / "monitor").is_dir()
    assert not (unit / "result.json").exists()


@pytest.mark.parametrize(
    "changed", [{"decisions": 60}, {"seed": 1}, {"eval_every": 25}, {"learner": {"lr": 1}}]
)
def test_other_settings_set_the_unit_aside(pilot, tmp_path: Path, changed: dict) -> None:
    unit = _unit(tmp_path / "u", SETTINGS, result=True)
    assert not pilot.finished(unit, {**SETTINGS, **changed})
    assert not (unit / "state.json").exists() and not (unit / "model.zip").exists()
    assert json.loads((unit / "result.1.json").read_text())["settings"] == SETTINGS


def test_monitors_keep_the_legs_of_the_checkpoint(pilot, tmp_path: Path) -> None:
    folder = tmp_path / "monitor"
    folder.mkdir()
    legs = "".join(f"{r},{n},{t}\n" for r, n, t in [(1, 4, 0.1), (2, 5, 0.2), (3, 6, 0.3)])
    (folder / "0.monitor.csv").write_text('#{"t_start": 0}\nr,l,t\n' + legs)
    pilot.trim_monitors(folder, per_env=9)  # legs ending at 4, 9 and 15 decisions
    assert [row["r"] for row in pilot.monitor_rows(folder)] == ["1", "2"]


def test_leg_summary_separates_driving_from_declaring(pilot) -> None:
    rows = [
        {"outcome": "goal", "in_radius": 3, "closest_m": 0.1, "false_stops": 0},
        {"outcome": "time limit", "in_radius": 5, "closest_m": 0.1, "false_stops": 2},
        {"outcome": "collision", "in_radius": 0, "closest_m": 2.0, "false_stops": 1},
        {"outcome": "time limit", "in_radius": 0, "closest_m": 3.0, "false_stops": 1},
    ]
    summary = pilot.leg_summary(rows)
    assert summary["success"] == 0.25
    assert summary["within_radius"] == 0.5
    assert summary["declared_when_within"] == 0.5  # reached twice, declared once
    assert summary["outcome time limit"] == 0.5
    assert summary["false_stops_per_leg"] == 1.0
    assert summary["median_closest_m"] == pytest.approx(1.05)
