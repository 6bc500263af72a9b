"""The benchmark's figure (``leaderboard.png``): success and SPL per row with their intervals,
and the paired differences in success, each row naming its agent: the pose sources of one
agent against each other, and each learnt model against the follower on the same pose
source."""

from __future__ import annotations

from pathlib import Path

from stsf_gym.experiments.benchmark.against_follower import follower_pairs
from stsf_gym.experiments.benchmark.trained import agent_name
from stsf_gym.io import save_figure


def row_label(row: dict) -> str:
    """``<agent> / <pose source>``: ``follower / stsf``, ``ppo-truth/seed-0 / truth``."""
    return f"{agent_name(row['agent'])} / {row['estimator']}"


def paired_rows(summary: dict) -> list[tuple[str, dict]]:
    """``(label, success difference)`` of every paired comparison the figure draws."""
    rows = [
        (f"{agent_name(p['agent'])}: {p['first']} - {p['second']}", p["success_difference"])
        for p in summary["paired"]
    ]
    rows += [
        (f"{model} - follower, on {source}", paired)
        for model, source, paired in follower_pairs(summary)
    ]
    return rows


def plot_leaderboard(summary: dict, path: str | Path) -> Path:
    """Success rate (Wilson 95 % intervals) and SPL (bootstrap 95 % intervals) per row, and
    the paired differences in success with their intervals (red: the interval excludes 0)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = sorted(summary["rows"], key=lambda r: r["success_rate"]["mean"])
    labels = [row_label(r) for r in rows]
    pairs = paired_rows(summary)
    fig, axes = plt.subplots(1, 3, figsize=(16, 0.5 * max(len(rows), len(pairs)) + 2))
    for ax, key, ci, title in (
        (axes[0], "success_rate", "success_ci95", "success rate (Wilson 95 % CI)"),
        (axes[1], "spl", "spl_ci95", "SPL (stratified bootstrap 95 % CI)"),
    ):
        means = [r[key]["mean"] for r in rows]
        errors = [
            [m - r[ci][0] for m, r in zip(means, rows, strict=True)],
            [r[ci][1] - m for m, r in zip(means, rows, strict=True)],
        ]
        ax.errorbar(means, range(len(rows)), xerr=errors, fmt="o", capsize=4)
        ax.set(yticks=range(len(rows)), yticklabels=labels, xlim=(-0.02, 1.02), title=title)
        ax.grid(alpha=0.3)
    ax = axes[2]
    for i, (_, s) in enumerate(pairs):
        differs = s["low"] > 0 or s["high"] < 0
        ax.errorbar(
            s["difference"],
            i,
            xerr=[[s["difference"] - s["low"]], [s["high"] - s["difference"]]],
            fmt="o",
            capsize=4,
            color="tab:red" if differs else "tab:gray",
        )
    ax.axvline(0, color="k", lw=0.8)
    ax.set(
        yticks=range(len(pairs)),
        yticklabels=[label for label, _ in pairs],
        title="paired success difference (95 % CI)",
    )
    ax.grid(alpha=0.3)
    worlds, episodes = summary["worlds"], rows[0]["episodes"] if rows else 0
    fig.suptitle(
        f"Suite {summary['suite']}: declared arrival, {episodes} test worlds "
        f"{worlds['world_seeds'][0]}-{worlds['world_seeds'][1]}"
    )
    fig.tight_layout()
    return save_figure(fig, path)
