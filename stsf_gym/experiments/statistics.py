"""Metrics and statistics of episodes: table rows, NEES consistency, error curves.

Every experiment scores its episodes here, so a metric means the same in each table.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import chi2

from stsf_gym.experiments.episodes import EpisodeResult


def rms(values) -> float:
    """Root mean square of ``values`` (NaN when there are none)."""
    return float(np.sqrt(np.mean(np.square(values)))) if len(values) else math.nan


def mean_std(values) -> str:
    """``"mean ± std"`` of the finite ``values`` (NaN left out), ``"-"`` when none remain."""
    values = [v for v in values if not np.isnan(v)]
    return f"{np.mean(values):.3f} ± {np.std(values):.3f}" if values else "-"


def summarise(estimator: str, episodes: list[EpisodeResult]) -> dict:
    """One table row: success, failures, errors, consistency, landmark matching, timing."""
    final = [e.errors[-1] for e in episodes]
    worst = [max(e.errors) for e in episodes]
    heading = [rms(e.heading_errors) for e in episodes]
    nees_in_bounds, (lo, hi) = nees_consistency(episodes)
    failed = [e.distance for e in episodes if e.outcome != "goal"]
    frames = sum(e.frames for e in episodes)
    stages = sorted({k for e in episodes for k in e.stage_ms_per_step})
    return {
        "estimator": estimator,
        "episodes": len(episodes),
        "success rate": np.mean([e.outcome == "goal" for e in episodes]),
        "collisions": sum(e.outcome == "collision" for e in episodes),
        "distance before failure (m)": float(np.mean(failed)) if failed else "-",
        "final error (m)": mean_std(final),
        "RMS error (m)": mean_std([rms(e.errors) for e in episodes]),
        "max error (m)": mean_std(worst),
        "RMS heading error (deg)": mean_std(np.degrees(heading)),
        "NEES": float(np.mean([e.nees for e in episodes])),
        "NEES 95% bounds": f"{lo:.2f}-{hi:.2f}",
        "NEES in bounds": nees_in_bounds,
        "landmark in view": sum(e.frames_in_view for e in episodes)
        / max(1, sum(e.camera_frames for e in episodes)),
        "landmark match rate": sum(e.frames_matched for e in episodes) / frames if frames else "-",
        "ms per step": ", ".join(
            f"{k} {np.mean([e.stage_ms_per_step.get(k, 0.0) for e in episodes]):.2f}"
            for k in stages
        ),
    }


def nees_consistency(episodes: list[EpisodeResult]) -> tuple[float, tuple[float, float]]:
    """Monte-Carlo NEES test (Bar-Shalom, Li and Kirubarajan 2001, sect. 5.4).

    At each stored sample k, the NEES averaged over the M runs times M is chi-square with 3M
    degrees of freedom for a consistent estimator; returns the fraction of samples (up to the
    shortest run) whose average lies inside the two-sided 95 % bounds, and the bounds. The
    bounds also serve for the time average in the table (time-averaging only narrows the
    spread, so they are conservative for it); samples within a run are correlated, so using
    every step as a degree of freedom would give far too narrow bounds.
    """
    m = len(episodes)
    lo, hi = chi2.ppf([0.025, 0.975], 3 * m) / m
    length = min(len(e.nees_trace) for e in episodes)
    average = np.mean([e.nees_trace[:length] for e in episodes], axis=0)
    return float(np.mean((average >= lo) & (average <= hi))), (float(lo), float(hi))


def error_curves(episodes: list[EpisodeResult], grid: np.ndarray):
    """Mean position and heading error of the episodes on a grid of distance driven."""
    position, heading = [], []
    for e in episodes:
        inside = grid <= e.travelled[-1]
        position.append(np.where(inside, np.interp(grid, e.travelled, e.errors), np.nan))
        h = np.degrees(np.abs(e.heading_errors))
        heading.append(np.where(inside, np.interp(grid, e.travelled, h), np.nan))
    return mean_over_episodes(position), mean_over_episodes(heading)


def mean_over_episodes(curves: list[np.ndarray]) -> np.ndarray:
    """Mean of the curves where at least one episode got that far (NaN elsewhere)."""
    stacked = np.array(curves)
    count = np.sum(~np.isnan(stacked), axis=0)
    total = np.nansum(stacked, axis=0)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)
