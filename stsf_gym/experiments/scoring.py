"""Scoring recorded episodes with the standard metrics, as rows of the results schema.

:func:`episode_metrics` gives one episode's numbers (:mod:`stsf_gym.metrics`: ATE, RPE per
metre over :data:`RPE_DELTA_M`, NEES, NIS, ...); :func:`summarise` gives a results row over
episodes: each metric a :func:`stsf_gym.results.stat`, plus the Monte-Carlo consistency tests
of NEES and NIS with their chi-square bounds.
"""

from __future__ import annotations

import math
from collections import Counter
from typing import TYPE_CHECKING

import numpy as np

from stsf_gym.metrics import ate_rmse, chi2_bounds, fraction_inside, rpe_per_metre
from stsf_gym.results import stat, stats

if TYPE_CHECKING:
    from stsf_gym.experiments.episodes import EpisodeResult

#: Travelled distance of the RPE's pose pairs (m): ``evo_rpe --delta 1 --delta_unit m``.
RPE_DELTA_M = 1.0


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def episode_metrics(episode: EpisodeResult) -> dict[str, float | None]:
    """The metrics of one episode (None where it has none, e.g. no landmark frames)."""
    errors = episode.errors
    rpe = rpe_per_metre(episode.true_poses, episode.estimates, RPE_DELTA_M)
    nis = np.asarray(episode.nis, dtype=float).reshape(-1, 2)
    return {
        "success_rate": float(episode.outcome == "goal"),
        "collision_rate": float(episode.outcome == "collision"),
        "ate_rmse_m": ate_rmse(episode.true_xy, episode.estimate_xy),
        "rpe_trans_m_per_m": _finite(rpe.trans_m_per_m),
        "rpe_rot_deg_per_m": _finite(rpe.rot_deg_per_m),
        "final_error_m": float(errors[-1]),
        "max_error_m": float(np.max(errors)),
        "rms_heading_error_deg": math.degrees(math.sqrt(np.mean(episode.heading_errors**2))),
        "path_error_rms_m": float(np.sqrt(np.mean(np.square(episode.path_errors)))),
        "nees_mean": _finite(episode.nees),
        "nis_mean": float(nis[:, 0].mean()) if len(nis) else None,
        "match_rate": episode.frames_matched / episode.frames if episode.frames else None,
        "landmark_in_view": episode.frames_in_view / episode.camera_frames
        if episode.camera_frames
        else None,
    }


def summarise(estimator: str, episodes: list[EpisodeResult], agent: str | None = None) -> dict:
    """One results row: the metrics over ``episodes`` and their consistency tests."""
    per_episode = stats([episode_metrics(e) for e in episodes])
    nees_in_bounds, nees_bounds = nees_consistency(episodes)
    nis_in_bounds, nis_bounds = nis_consistency(episodes)
    stages = sorted({k for e in episodes for k in e.stage_ms_per_step})
    failed = [e.distance for e in episodes if e.outcome != "goal"]
    return {
        "agent": agent or episodes[0].spec["agent"],
        "estimator": estimator,
        "episodes": len(episodes),
        "seeds": [e.spec["seed"] for e in episodes],
        **{k: per_episode[k] for k in ("success_rate", "collision_rate")},
        "distance_before_failure_m": stat(failed),
        **{k: v for k, v in per_episode.items() if k not in ("success_rate", "collision_rate")},
        "nees_bounds": nees_bounds,
        "nees_in_bounds": nees_in_bounds,
        "nis_bounds": nis_bounds,
        "nis_in_bounds": nis_in_bounds,
        "ms_per_step": {k: stat(e.stage_ms_per_step.get(k, 0.0) for e in episodes) for k in stages},
    }


def nees_consistency(episodes: list[EpisodeResult]) -> tuple[float, list[float]]:
    """Monte-Carlo NEES test (Bar-Shalom, Li and Kirubarajan 2001, sect. 5.4).

    At each step k, the NEES averaged over the M runs times M is chi-square with 3M degrees of
    freedom for a consistent estimator; returns the fraction of steps (up to the shortest run)
    whose average lies inside the two-sided 95 % bounds, and the bounds. The bounds also serve
    for the time average in the table (time-averaging only narrows the spread, so they are
    conservative for it); steps within a run are correlated, so using every step as a degree
    of freedom would give far too narrow bounds.
    """
    bounds = chi2_bounds(3, len(episodes))
    length = min(len(e.times) for e in episodes)
    average = np.mean([e.nees_trace[:length] for e in episodes], axis=0)
    return fraction_inside(average, bounds), list(bounds)


def nis_consistency(episodes: list[EpisodeResult]) -> tuple[float | None, list[float] | None]:
    """Fraction of the innovations whose NIS lies inside the 95 % chi-square bounds of its
    dimension, and the bounds of the most common dimension (None without innovations)."""
    nis = np.concatenate([np.reshape(e.nis, (-1, 2)) for e in episodes])
    if not len(nis):
        return None, None
    inside = [fraction_inside([v], chi2_bounds(int(dof))) for v, dof in nis]
    dof = Counter(int(d) for d in nis[:, 1]).most_common(1)[0][0]
    return float(np.mean(inside)), list(chi2_bounds(dof))
