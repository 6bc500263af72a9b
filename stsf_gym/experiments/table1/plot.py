"""Table I as a figure: per row, both methods' errors beside the paper's and the bound."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stsf_gym.experiments.plotting.maps import pyplot
from stsf_gym.io import save_figure


def plot_table1(rows: list[dict], path: Path) -> Path:
    """Per row, conventional fusion's and STSF's RMS error (and STSF's with the joint covariance
    where the rows have it; bars: spread over seeds; hollow: median) beside the paper's errors
    and the stereo bound, on a log scale."""
    plt = pyplot()
    x = np.arange(len(rows))
    fig, ax = plt.subplots(figsize=(9, 4.5))
    series = [
        (-0.15, "conventional", "conventional (ours)", "tab:orange"),
        (0.0, "stsf", "STSF (ours)", "tab:blue"),
        (0.15, "stsf_joint", "STSF, joint covariance (ours)", "tab:green"),
    ]
    for offset, name, label, color in [s for s in series if f"{s[1]}_m" in rows[0]]:
        rms = np.array(
            [np.nan if r[f"{name}_rms_error_m"] is None else r[f"{name}_rms_error_m"] for r in rows]
        )
        spread = np.array([r[f"{name}_error_m"]["std"] or 0.0 for r in rows])
        ax.errorbar(x + offset, rms, yerr=spread, fmt="o", color=color, capsize=3, label=label)
        median = [
            np.nan if r[f"{name}_median_error_m"] is None else r[f"{name}_median_error_m"]
            for r in rows
        ]
        ax.plot(x + offset, median, "D", mfc="none", color=color, label=f"{label}, median")
    for name, label, color in (
        ("paper_conventional_error_m", "conventional (paper)", "tab:orange"),
        ("paper_stsf_error_m", "STSF (paper)", "tab:blue"),
    ):
        paper = [r.get(name, np.nan) for r in rows]
        ax.plot(x, paper, "--", marker="x", color=color, alpha=0.6, label=label)
    ax.plot(x, [r["bound_m"] for r in rows], ":", color="0.4", label="bound sqrt(2) Z² σ/(f b)")
    ax.set_xticks(
        x,
        [
            f"{r['row']}: {r['world_distance_m']:g} m\nb = {r['baseline_m']['mean']:.2f} m"
            for r in rows
        ],
    )
    ax.set_yscale("log")
    ax.set_ylabel("distance error (m)")
    ax.set_title("Table I: distance to the landmark, error per place (RMS over seeds, ± spread)")
    ax.set_ylim(bottom=0.003)  # room for the legend below the bound
    ax.legend(fontsize=7, ncol=3, loc="lower center")
    fig.tight_layout()
    try:
        return save_figure(fig, path)
    finally:
        plt.close(fig)
