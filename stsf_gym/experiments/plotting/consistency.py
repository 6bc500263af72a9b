"""``nees.png``: NEES over time with its chi-square bounds, one panel per estimator.

Each panel shows the NEES averaged over the estimator's M episodes at every step (up to the
shortest episode), the band of the Monte-Carlo test's two-sided 95 % bounds
(:func:`stsf_gym.metrics.chi2_bounds` with 3 dof and M runs) and the expected value 3, on a
logarithmic axis: an overconfident estimator rises above the band, a conservative one falls
under it.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from stsf_gym.io import save_figure
from stsf_gym.metrics import chi2_bounds
from stsf_gym.results import render

if TYPE_CHECKING:
    from stsf_gym.experiments.episodes import EpisodeResult


def plot_nees(by_estimator: dict[str, list[EpisodeResult]], path: Path) -> Path:
    """:func:`nees_figure` saved as ``path``."""
    return save_figure(nees_figure(by_estimator), path)


def nees_figure(by_estimator: dict[str, list[EpisodeResult]]) -> Figure:
    """One panel per estimator: the Monte-Carlo average NEES against time, with bounds; each
    panel titled on two lines (the name, then the runs and bounds), so no title runs into the
    next panel's."""
    fig = Figure(figsize=(4.2 * len(by_estimator), 3.8), layout="constrained")
    axes = fig.subplots(1, len(by_estimator), squeeze=False, sharey=True)[0]
    for ax, (name, episodes) in zip(axes, by_estimator.items(), strict=True):
        length = min(len(e.times) for e in episodes)
        times = np.asarray(episodes[0].times[:length])
        average = np.mean([e.nees_trace[:length] for e in episodes], axis=0)
        lo, hi = chi2_bounds(3, len(episodes))
        ax.fill_between(times, lo, hi, color="tab:green", alpha=0.2, label="95 % bounds")
        ax.axhline(3.0, color="tab:green", lw=0.8)
        ax.plot(times, np.maximum(average, 1e-3), color="tab:blue", lw=0.9, label="mean NEES")
        ax.set_yscale("log")
        ax.set_xlabel("time (s)")
        ax.set_title(f"{name}\n{len(episodes)} runs, 95 % bounds {render([lo, hi])}", fontsize=10)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("NEES (3 dof)")
    axes[0].legend(fontsize=8)
    return fig
