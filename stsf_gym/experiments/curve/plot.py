"""``curve.png``: success rate, collision rate and path-following error against measured ATE.

One colour per agent: its dial (``degraded-truth`` at each level) as a line (path error with
error bars of one std over seeds), its tolerated ATE as a dashed vertical line, and each real
estimator it drove on as a marker (one shape per estimator) at that estimator's measured ATE.
The ATE axis is logarithmic (the estimators span three orders of magnitude).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from stsf_gym.io import save_figure

PANELS = (
    ("success_rate", "success rate"),
    ("collision_rate", "collision rate"),
    ("path_error_rms_m", "path-following error, RMS (m)"),
)
MARKERS = {
    "odometry": "s",
    "conventional": "^",
    "conventional-filter": "v",
    "stsf": "o",
    "ekf": "D",
}


def _xy(points: list[dict], key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Measured ATE and the metric ``key`` (mean, std) of each point with both."""
    kept = [p for p in points if p["ate_rmse_m"]["mean"] is not None and p[key]["mean"] is not None]
    ate = np.array([p["ate_rmse_m"]["mean"] for p in kept])
    return ate, np.array([p[key]["mean"] for p in kept]), np.array([p[key]["std"] for p in kept])


def plot_curve(summary: dict, path: Path) -> Path:
    """The figure of ``summary`` (as in curve.json), written to ``path``."""
    fig = Figure(figsize=(5.2 * len(PANELS), 4.4))
    axes = fig.subplots(1, len(PANELS))
    colours = [f"C{i}" for i in range(10)]
    for curve, colour in zip(summary["curves"], colours, strict=False):
        agent = curve["agent"]
        points = [p for p in summary["estimators"] if p["agent"] == agent]
        for ax, (key, _) in zip(axes, PANELS, strict=True):
            ate, mean, std = _xy(curve["levels"], key)
            spread = None if key.endswith("rate") else std  # a rate's spread is its mean's
            ax.errorbar(ate, mean, spread, color=colour, marker=".", capsize=2)
            if curve["tolerated_ate_m"] is not None:
                ax.axvline(curve["tolerated_ate_m"], color=colour, ls="--", lw=0.8)
            for point in points:
                x, y, _ = _xy([point], key)
                if len(x):
                    marker = MARKERS.get(point["estimator"], "*")
                    ax.plot(x, y, marker, color=colour, ms=8, mfc="none", mew=1.5)
    for ax, (key, name) in zip(axes, PANELS, strict=True):
        ax.set_xscale("log")
        ax.set(xlabel="measured ATE (m)", ylabel=name)
        ax.grid(alpha=0.3, which="both")
        if key.endswith("rate"):
            ax.set_ylim(-0.05, 1.05)
    axes[0].axhline(summary["required_success_rate"], color="0.5", lw=0.8)
    agents = [
        Line2D([], [], color=colour, marker=".", label=f"{curve.get('label', curve['agent'])}")
        for curve, colour in zip(summary["curves"], colours, strict=False)
    ]
    estimators = sorted({p["estimator"] for p in summary["estimators"]}, key=list(MARKERS).index)
    markers = [
        Line2D([], [], ls="", marker=MARKERS[e], color="0.3", mfc="none", label=e)
        for e in estimators
    ]
    axes[0].legend(handles=agents, title="degraded truth", fontsize=7, loc="lower left")
    if markers:
        axes[1].legend(handles=markers, title="estimators", fontsize=7, loc="upper left")
    fig.suptitle(
        f"How good must localization be? {summary['world']}, seeds "
        f"{summary['seeds'][0]}-{summary['seeds'][1]} (dashed: tolerated ATE at "
        f">= {summary['required_success_rate']:.0%} success)"
    )
    fig.tight_layout()
    return save_figure(fig, path)
