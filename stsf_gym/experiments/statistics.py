"""Metrics and statistics of episodes: results rows, NEES and NIS consistency, error curves.

Every experiment scores its episodes here, so a metric means the same in each table.
:func:`episode_metrics` gives one episode's numbers with the standard metrics of
:mod:`stsf_gym.metrics` (ATE, RPE per metre over :data:`RPE_DELTA_M`, NEES, NIS, ...);
:func:`summarise` gives a row of the results schema over episodes: each metric a
:func:`stsf_gym.results.stat`, plus the Monte-Carlo consistency tests of NEES and NIS with their
chi-square bounds.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from stsf_gym.experiments.episodes import EpisodeResult
from stsf_gym.metrics import (
    ate_rmse,
    chi2_bounds,
    fraction_inside,
    rpe_per_metre,
    time_averaged_nees_bounds,
)
from stsf_gym.results import finite_or_none, stat, stats

#: Travelled distance of the RPE's pose pairs (m): ``evo_rpe --delta 1 --delta_unit m``.
RPE_DELTA_M = 1.0


def episode_metrics(episode: EpisodeResult) -> dict[str, float | None]:
    """The metrics of one episode (None where it has none, e.g. no landmark frames)."""
    errors = episode.errors
    rpe = rpe_per_metre(episode.true_poses, episode.estimates, RPE_DELTA_M)
    nis = np.asarray(episode.nis, dtype=float).reshape(-1, 2)
    ate = ate_rmse(episode.true_xy, episode.estimate_xy)
    floor = None if episode.floor_errors is None else rms(episode.floor_errors)
    return {
        "success_rate": float(episode.outcome == "goal"),
        "collision_rate": float(episode.outcome == "collision"),
        "time_limit_rate": float(episode.outcome == "time"),  # neither reached nor failed
        "ate_rmse_m": ate,
        "floor_ate_m": floor,
        "ate_vs_floor": None if not floor else ate / floor,
        "rpe_trans_m_per_m": finite_or_none(rpe.trans_m_per_m),
        "rpe_rot_deg_per_m": finite_or_none(rpe.rot_deg_per_m),
        "final_error_m": float(errors[-1]),
        "max_error_m": float(np.max(errors)),
        "rms_heading_error_deg": math.degrees(rms(episode.heading_errors)),
        "path_error_rms_m": rms(episode.path_errors),
        "nees_mean": finite_or_none(episode.nees),
        "nis_mean": float(nis[:, 0].mean()) if len(nis) else None,
        "match_rate": episode.frames_matched / episode.frames if episode.frames else None,
        "landmark_in_view": episode.frames_in_view / episode.camera_frames
        if episode.camera_frames
        else None,
    }


OUTCOME_RATES = ("success_rate", "collision_rate", "time_limit_rate")  # first in a row


def summarise(estimator: str, episodes: list[EpisodeResult], agent: str | None = None) -> dict:
    """One results row: the metrics over ``episodes`` and their consistency tests."""
    per_episode = stats([episode_metrics(e) for e in episodes])
    nees_in_bounds, nees_bounds = nees_consistency(episodes)
    nees_time = nees_time_average(episodes)
    nis_in_bounds, nis_bounds = nis_consistency(episodes)
    stages = sorted({k for e in episodes for k in e.stage_ms_per_step})
    failed = [e.distance for e in episodes if e.outcome != "goal"]
    return {
        "agent": agent or episodes[0].spec["agent"],
        "estimator": estimator,
        "episodes": len(episodes),
        "seeds": [e.spec["seed"] for e in episodes],
        **{k: per_episode[k] for k in OUTCOME_RATES},
        "distance_before_failure_m": stat(failed),
        **{k: v for k, v in per_episode.items() if k not in OUTCOME_RATES},
        "nees_bounds": nees_bounds,
        "nees_in_bounds": nees_in_bounds,
        **nees_time,
        "nis_bounds": nis_bounds,
        "nis_in_bounds": nis_in_bounds,
        "ms_per_step": {k: stat(e.stage_ms_per_step.get(k, 0.0) for e in episodes) for k in stages},
    }


def nees_consistency(episodes: list[EpisodeResult]) -> tuple[float, list[float]]:
    """Monte-Carlo NEES test (Bar-Shalom, Li and Kirubarajan 2001, sect. 5.4).

    At each step k, the NEES averaged over the M runs times M is chi-square with 3M degrees of
    freedom for a consistent estimator; returns the fraction of steps (up to the shortest run)
    whose average lies inside the two-sided 95 % bounds, and the bounds. These are per-step
    bounds: the time average is judged by :func:`nees_time_average` against its own.
    """
    bounds = chi2_bounds(3, len(episodes))
    length = min(len(e.times) for e in episodes)
    average = np.mean([e.nees_trace[:length] for e in episodes], axis=0)
    return fraction_inside(average, bounds), list(bounds)


def nees_time_average(episodes: list[EpisodeResult]) -> dict:
    """The time average of the Monte-Carlo NEES (averaged over the runs at each step, up to
    the shortest run) judged against bounds of its own degrees of freedom, ``3 M K / tau``
    for M runs of K steps whose NEES has autocorrelation time tau
    (:func:`stsf_gym.metrics.time_averaged_nees_bounds`): ``nees_time_average``,
    ``nees_time_bounds``, ``nees_effective_steps`` (K / tau) and ``nees_verdict``: 0 inside,
    +1 above (over-confident), -1 below (a covariance too pessimistic)."""
    length = min(len(e.times) for e in episodes)
    trace = np.mean([e.nees_trace[:length] for e in episodes], axis=0)
    average, (low, high), effective = time_averaged_nees_bounds(trace, 3, len(episodes))
    verdict = 1 if average > high else -1 if average < low else 0
    return {
        "nees_time_average": average,
        "nees_time_bounds": [low, high],
        "nees_effective_steps": effective,
        "nees_verdict": verdict,
    }


def nis_consistency(episodes: list[EpisodeResult]) -> tuple[float | None, list[float] | None]:
    """Fraction of the innovations whose NIS lies inside the 95 % chi-square bounds of its
    dimension, and the bounds of the most common dimension (None without innovations)."""
    nis = np.concatenate([np.reshape(e.nis, (-1, 2)) for e in episodes])
    if not len(nis):
        return None, None
    inside = [fraction_inside([v], chi2_bounds(int(dof))) for v, dof in nis]
    dof = Counter(int(d) for d in nis[:, 1]).most_common(1)[0][0]
    return float(np.mean(inside)), list(chi2_bounds(dof))


def rms(values) -> float:
    """Root mean square of ``values`` (NaN when there are none)."""
    return float(np.sqrt(np.mean(np.square(values)))) if len(values) else math.nan


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
