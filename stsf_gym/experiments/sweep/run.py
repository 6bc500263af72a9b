"""``stsf-gym sweep FILE``: run the cells of a sweep file and summarise them.

Each cell's result is a row of ``<out>/cells.sqlite``, written when the cell finishes;
a rerun skips finished cells and retries failed ones. The file is read by
:mod:`stsf_gym.experiments.sweep.spec`, the summary written by
:mod:`stsf_gym.experiments.sweep.report`.
"""

from __future__ import annotations

from pathlib import Path

from stsf_gym.experiments.jobs.cells import CELL_JOBS, cell_name
from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.experiments.sweep.report import write_report
from stsf_gym.experiments.sweep.spec import load_sweep


def run_sweep(
    path: str | Path,
    out: str | Path | None = None,
    backend: str = "local",
    workers: int = 2,
    address: str | None = None,
    seed: int = 0,
    env: dict | None = None,
) -> dict:
    """Run every cell of the sweep in ``path`` not already finished in ``out``; summarise."""
    sweep = load_sweep(path, seed, env)
    out = Path(out) if out is not None else Path("out/sweeps") / sweep.name
    cells = [_with_run_folder(cell, out) for cell in sweep.cells]
    ran = run_jobs(
        CELL_JOBS,
        cells,
        out / "cells.sqlite",
        f"sweep {sweep.name}",
        backend,
        workers,
        address,
        unit="cell",
    )
    return write_report(sweep, ran.results, out, ran.configs)


def _with_run_folder(cell: dict, out: Path) -> dict:
    """A training cell keeps its run (model, logs, checkpoints) in ``<out>/runs/<cell>/``."""
    if cell["kind"] != "train":
        return cell
    return {**cell, "out": str((out / "runs" / cell_name(cell)).resolve())}
