"""Learning curves of training means (the clone, the fine-tuned agent, plain RL, ...): val
success and val return against env steps and against wall time, IQM over training seeds with
95 % bootstrap intervals, one figure per suite.

Each ``FOLDER`` is one means (the ``OUT`` of ``stsf-gym train --seeds N``, or of one seed).
Every run logs its evaluations on the val worlds, the same worlds each time: the demonstration
rounds in ``demonstrations.json``, the reward stage's in ``evaluations.json``
(:func:`~stsf_gym.agents.training.training_log.curve_points`). At each evaluation the score
matrices ``seeds x val worlds`` (success 0/1, return) are aggregated as rliable does: the
interquartile mean over seeds of each seed's mean, its 95 % interval from resampling worlds and
seeds (:func:`~stsf_gym.experiments.benchmark.intervals.seed_iqm`, a seeded numpy bootstrap).
rliable 1.2.0 itself requires arch (with statsmodels), absl-py, seaborn, pandas and scipy (its
setup.py); arch and statsmodels are in no environment of the project, for this one function.
An evaluation's x position is its median over the seeds.

Usage::

    python benchmarks/learning_curves.py FOLDER [FOLDER ...] [--labels a,b] --out DIR

Writes ``curves.json`` (numbers under ``means``, and the run's provenance), ``curves.md`` and
``curves-<suite>.png`` to ``DIR``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from stsf_gym.agents.training.training_log import curve_points
from stsf_gym.experiments.benchmark.intervals import seed_iqm
from stsf_gym.io import save_figure, write_atomic, write_json
from stsf_gym.results.provenance import provenance

METRICS = {"success": ("val_episodes", "val success"), "return": ("val_returns", "val return")}
AXES = {
    "control_steps": ("env steps (thousands of 0.1 s steps)", 1e3),
    "wall_time_s": ("wall time (min)", 60),
}


#: How each stage's points are drawn: the demonstration rounds dashed, learning from reward
#: solid (its first point the round it starts from, :func:`with_stage_start`).
STAGE_STYLES = {"demonstrations": "s--", "reward": "o-"}


def runs_of(folder: Path) -> list[Path]:
    """The training runs in ``folder``: its ``seed-*`` folders, or itself."""
    return sorted(folder.glob("seed-*")) or [folder]


def suite_of(run: Path) -> str:
    """The suite a run trained on (``train.json``; a world's name when none)."""
    record = json.loads((run / "train.json").read_text())
    return record.get("suite") or record["world"]


def with_stage_start(run: Path, points: list[dict]) -> list[dict]:
    """``points`` of a fine-tuning run with the reward stage's start added: the demonstration
    round the run kept (``train.json``), the policy that stage starts from, placed at the
    demonstrations' end. Without it the reward stage's line would start at the last round,
    which the stage never drove."""
    demonstrations = [p for p in points if p["stage"] == "demonstrations"]
    reward = [p for p in points if p["stage"] == "reward"]
    record = json.loads((run / "train.json").read_text()).get("demonstrations") or {}
    kept = record.get("kept_round")
    if kept is None or not reward or not demonstrations:
        return points
    end = demonstrations[-1]
    start = demonstrations[kept] | {
        "stage": "reward",
        "control_steps": end["control_steps"],
        "wall_time_s": end["wall_time_s"],
    }
    return [*demonstrations, start, *reward]


def curve(folder: Path) -> dict:
    """The means' suite and, per evaluation every run made, the median x positions and the
    IQM over seeds of val success and return with their 95 % intervals."""
    runs = runs_of(folder)
    logs = [with_stage_start(run, points) for run in runs if (points := curve_points(run))]
    if not logs:
        raise SystemExit(f"{folder}: no evaluations logged in it or its seed-* folders")
    points = []
    for index in range(min(map(len, logs))):
        rows = [log[index] for log in logs]
        point = {"stage": rows[0]["stage"], "seeds": len(rows)}
        point |= {axis: float(np.median([r[axis] for r in rows])) for axis in AXES}
        for name, (key, _) in METRICS.items():
            interval = seed_iqm([r[key] for r in rows])  # seeds x val worlds
            point[f"{name}_iqm"] = interval["estimate"]
            point[f"{name}_ci95"] = [interval["low"], interval["high"]]
            point[f"{name}_per_seed"] = interval["per_run"]
        points.append(point)
    return {"suite": suite_of(runs[0]), "points": points}


def plot(curves: dict[str, dict], suite: str, path: Path) -> Path:
    """Success and return (rows) against env steps and wall time (columns) for ``suite``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex="col", sharey="row")
    for label, means in curves.items():
        if means["suite"] != suite:
            continue
        seeds, colour = means["points"][0]["seeds"], f"C{list(curves).index(label)}"
        for stage, style in STAGE_STYLES.items():
            points = [p for p in means["points"] if p["stage"] == stage]
            if not points:
                continue
            for row, (name, (_, ylabel)) in enumerate(METRICS.items()):
                y = np.array([p[f"{name}_iqm"] for p in points])
                low, high = np.array([p[f"{name}_ci95"] for p in points]).T
                for col, (axis, (xlabel, scale)) in enumerate(AXES.items()):
                    x = np.array([p[axis] for p in points]) / scale
                    ax = axes[row, col]
                    ax.plot(x, y, style, color=colour, label=f"{label}, {stage} ({seeds} seeds)")
                    ax.fill_between(x, low, high, alpha=0.15, color=colour)
                    ax.set(xlabel=xlabel if row else "", ylabel=f"{ylabel} (IQM, 95 % CI)")
    axes[0, 0].set(ylim=(-0.05, 1.05), title=f"{suite}: val worlds")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        if ax.lines:
            ax.legend(fontsize="small")
    try:
        return save_figure(fig, path)
    finally:
        plt.close(fig)


def table(curves: dict[str, dict]) -> str:
    """Every means' points as a Markdown table."""
    lines = [
        "| means | suite | stage | seeds | env steps | wall time (s) "
        "| val success IQM (95 % CI) | val return IQM (95 % CI) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for label, means in curves.items():
        for p in means["points"]:
            cells = [
                f"{p[f'{n}_iqm']:.2f} ({p[f'{n}_ci95'][0]:.2f} to {p[f'{n}_ci95'][1]:.2f})"
                for n in METRICS
            ]
            lines.append(
                f"| {label} | {means['suite']} | {p['stage']} | {p['seeds']} | "
                f"{p['control_steps']:.0f} | {p['wall_time_s']:.0f} | {' | '.join(cells)} |"
            )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--labels", help="one label per folder, comma-separated (folder names)")
    parser.add_argument("--out", type=Path, default=Path("out/learning-curves"))
    args = parser.parse_args()
    labels = args.labels.split(",") if args.labels else [f.name for f in args.folders]
    if len(labels) != len(args.folders):
        raise SystemExit(f"--labels names {len(labels)} means for {len(args.folders)} folders")
    curves = {label: curve(folder) for label, folder in zip(labels, args.folders, strict=True)}
    write_json(args.out / "curves.json", {"means": curves, "provenance": provenance()})
    write_atomic(args.out / "curves.md", table(curves))
    for suite in sorted({means["suite"] for means in curves.values()}):
        plot(curves, suite, args.out / f"curves-{suite}.png")
    print(table(curves))


if __name__ == "__main__":
    main()
