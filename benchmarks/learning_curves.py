"""Learning curves of the demonstration stage: success on the validation worlds against control
steps and against wall time, IQM over training seeds with a stratified bootstrap interval.

Each ``FOLDER`` is one means tried (the ``OUT`` of ``stsf-gym train --seeds N``, or of one
seed): its runs' ``demonstrations.json`` log every round (control steps, wall time, and the
success of each validation episode, the same worlds every round). At each round the score
matrix ``seeds x val worlds`` is aggregated as rliable does: the interquartile mean over seeds
of each seed's success rate, its 95 % interval from resampling worlds and seeds
(:func:`~stsf_gym.experiments.benchmark.intervals.seed_iqm`). The x position of a round is its
median over the seeds.

Usage::

    python benchmarks/learning_curves.py FOLDER [FOLDER ...] [--labels a,b] --out DIR

Writes ``curves.json`` (numbers only), ``curves.md`` and ``curves.png`` to ``DIR``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from stsf_gym.agents.demonstrations.dagger import read_history
from stsf_gym.experiments.benchmark.intervals import seed_iqm
from stsf_gym.io import save_figure, write_atomic, write_json


def runs_of(folder: Path) -> list[Path]:
    """The training runs in ``folder``: its ``seed-*`` folders, or itself."""
    return sorted(folder.glob("seed-*")) or [folder]


def curve(folder: Path) -> list[dict]:
    """Per round done by every run of ``folder``: the IQM of val success with its interval and
    the median control steps and wall time."""
    histories = [read_history(run) for run in runs_of(folder)]
    histories = [h for h in histories if h]
    if not histories:
        raise SystemExit(f"{folder}: no demonstrations.json in it or its seed-* folders")
    points = []
    for round_ in range(min(len(h) for h in histories)):
        rows = [h[round_] for h in histories]
        interval = seed_iqm([row["val_episodes"] for row in rows])  # seeds x val worlds
        points.append(
            {
                "round": round_,
                "seeds": len(rows),
                "val_worlds": len(rows[0]["val_episodes"]),
                "control_steps": float(np.median([r["control_steps"] for r in rows])),
                "wall_time_s": float(np.median([r["wall_time_s"] for r in rows])),
                "success_iqm": interval["estimate"],
                "success_iqm_ci95": [interval["low"], interval["high"]],
                "success_per_seed": [r["val_success"] for r in rows],
            }
        )
    return points


def plot(curves: dict[str, list[dict]], path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for label, points in curves.items():
        success = np.array([p["success_iqm"] for p in points])
        low, high = np.array([p["success_iqm_ci95"] for p in points]).T
        for ax, key, scale in ((axes[0], "control_steps", 1e3), (axes[1], "wall_time_s", 60)):
            x = np.array([p[key] for p in points]) / scale
            ax.plot(x, success, "o-", label=f"{label} ({points[0]['seeds']} seeds)")
            ax.fill_between(x, low, high, alpha=0.2)
    axes[0].set(xlabel="control steps (thousands)", ylabel="val success (IQM, 95 % CI)")
    axes[1].set(xlabel="wall time (min)", ylabel="val success (IQM, 95 % CI)")
    for ax in axes:
        ax.set_ylim(-0.05, 1.05)
        ax.grid(alpha=0.3)
        ax.legend()
    try:
        return save_figure(fig, path)
    finally:
        plt.close(fig)


def table(curves: dict[str, list[dict]]) -> str:
    lines = [
        "| means | round | seeds | control steps | wall time (s) | val success IQM (95 % CI) |",
        "|---|---|---|---|---|---|",
    ]
    for label, points in curves.items():
        for p in points:
            low, high = p["success_iqm_ci95"]
            lines.append(
                f"| {label} | {p['round']} | {p['seeds']} | {p['control_steps']:.0f} | "
                f"{p['wall_time_s']:.0f} | {p['success_iqm']:.2f} ({low:.2f}-{high:.2f}) |"
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
    write_json(args.out / "curves.json", curves)
    write_atomic(args.out / "curves.md", table(curves))
    plot(curves, args.out / "curves.png")
    print(table(curves))


if __name__ == "__main__":
    main()
