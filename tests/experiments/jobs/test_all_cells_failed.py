"""A multi-cell command whose cells ALL fail reports the failed cells as it does one failure:
its files are written, each failed cell is named on stderr, no traceback; and it exits 1, as a
run with nothing to score has failed (one failed cell among finished ones exits 0)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from stsf_gym.estimators.base import PoseEstimator
from stsf_gym.experiments.jobs import cells
from stsf_gym.experiments.jobs.spec import failure
from stsf_gym.io import markdown_table


@dataclass(frozen=True)
class NoSettings:
    """A user's estimator without options."""


class RaisingEstimator(PoseEstimator):
    """A user's estimator with a bug: its first update raises."""

    settings_type: ClassVar[type] = NoSettings

    def __init__(self, settings: NoSettings) -> None:
        super().__init__()

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        raise RuntimeError("my estimator's bug")


RAISING = f"{__name__}:RaisingEstimator"


def _reported(err: str, cells: int) -> None:
    """Every failed cell named on stderr, once, and nothing else went wrong."""
    failed = [line for line in err.splitlines() if line.startswith("failed cell ")]
    assert len(failed) == cells and all("my estimator's bug" in line for line in failed), err
    assert "Traceback" not in err and "IndexError" not in err


def test_a_benchmark_whose_every_cell_fails_reports_them(run_cli, tmp_path):
    out = tmp_path / "out"
    argv = ["benchmark", "--suite", "corridor", "--worlds", "2", "--estimators", RAISING]
    code, err = run_cli(*argv, "--workers", "1", "--out", str(out))
    assert code == 1 and "all 2 cell(s) failed" in err
    _reported(err, cells=2)
    summary = json.loads((out / "corridor" / "results.json").read_text())
    assert summary["rows"] == [] and len(summary["failed"]) == 2
    board = (out / "corridor" / "leaderboard.md").read_text()
    assert "No rows: nothing finished." in board and "Cells that failed to run" in board
    assert (out / "corridor" / "leaderboard.png").is_file()


def test_a_sweep_whose_every_cell_fails_reports_them(run_cli, tmp_path):
    sweep = tmp_path / "broken.yaml"
    sweep.write_text(
        f"base: {{world: straight_10m, estimator: '{RAISING}', env: {{camera: {{mode: fast}}}}}}\n"
        "grid: {seeds: 2}\n"
    )
    out = tmp_path / "out"
    code, err = run_cli("sweep", str(sweep), "--workers", "1", "--out", str(out))
    assert code == 1 and "all 2 cell(s) failed" in err
    _reported(err, cells=2)
    summary = json.loads((out / "broken" / "results.json").read_text())
    assert summary["finished"] == 0 and len(summary["failed"]) == 2


def test_an_accuracy_curve_whose_every_cell_fails_reports_them(run_cli, tmp_path, monkeypatch):
    def broken_agent(cell: dict) -> dict:  # e.g. a user's agent that raises on every episode
        return failure(RuntimeError("my estimator's bug"))

    monkeypatch.setitem(cells.CELL_KINDS, "evaluate", cells.CellKind(broken_agent))
    out = tmp_path / "out"
    argv = ["accuracy-curve", "--levels", "1,2", "--seeds", "1", "--estimators", "odometry"]
    code, err = run_cli(*argv, "--workers", "1", "--out", str(out))
    assert code == 1 and "all 3 cell(s) failed" in err
    _reported(err, cells=3)
    assert json.loads((out / "curve.json").read_text())["failed"]


@pytest.mark.parametrize("columns", [None, ["a", "b"]])
def test_an_empty_table_is_written_not_raised(columns):
    table = markdown_table([], columns)
    assert table == (
        "No rows: nothing finished.\n" if columns is None else "| a | b |\n|---|---|\n"
    )
