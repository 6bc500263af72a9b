"""Standard localization metrics, defined as the field defines them (numpy and scipy only).

- **ATE** (absolute trajectory error): RMSE of the position error, *unaligned*: the simulator
  knows the true frame, so no Umeyama/SE(3) alignment is applied (``evo_ape`` without ``-a``).
- **RPE per metre** (relative pose error): the trajectory is cut into consecutive pairs of
  poses ``(i, j)`` whose *reference* path between them is at least ``delta`` metres long
  (evo's ``--delta D --delta_unit m --pairs_from_reference``); for each pair the error pose
  ``E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)`` (Q true, P estimated, as in the TUM RGB-D benchmark);
  translation and rotation RPE are the RMSE of ``|t(E)|`` and of the angle of ``R(E)``,
  divided by ``delta`` to give per metre values.
- **NEES** ``e^T P^-1 e`` of the pose error against the reported covariance, and **NIS**
  ``nu^T S^-1 nu`` of each measurement innovation; each chi-square with the error's dimension
  as degrees of freedom for a consistent filter, with two-sided bounds from
  :func:`chi2_bounds` and the fraction of values inside them; a time-averaged NEES is judged
  against bounds of its own degrees of freedom, the steps' correlation acknowledged
  (:func:`time_averaged_nees_bounds`).

Planar poses are ``[x, y, yaw]``; ``z = 0``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from stsf_gym.geometry import compose, inverse, wrap_angle

#: Two-sided probability of the chi-square bounds.
BOUNDS_PROBABILITY = 0.95


def ate_rmse(true_xy: ArrayLike, estimate_xy: ArrayLike) -> float:
    """Unaligned absolute trajectory error: RMSE of the position error (m)."""
    diff = np.asarray(estimate_xy, dtype=float) - np.asarray(true_xy, dtype=float)
    return float(np.sqrt(np.mean(np.sum(diff**2, axis=-1))))


def path_pairs(true_xy: ArrayLike, delta: float) -> list[tuple[int, int]]:
    """Consecutive index pairs whose path length along ``true_xy`` first reaches ``delta``."""
    if not delta > 0:
        raise ValueError(f"delta must be positive, got {delta}")
    steps = np.linalg.norm(np.diff(np.asarray(true_xy, dtype=float), axis=0), axis=1)
    ids, travelled = [0], 0.0
    for i, step in enumerate(steps, start=1):
        travelled += float(step)
        if travelled >= delta:
            ids.append(i)
            travelled = 0.0
    return list(itertools.pairwise(ids))


@dataclass(frozen=True)
class RelativeError:
    """RPE per metre over ``pairs`` pose pairs (NaN when the path is shorter than delta)."""

    trans_m_per_m: float
    rot_deg_per_m: float
    pairs: int


def rpe_per_metre(true_poses: ArrayLike, estimates: ArrayLike, delta: float = 1.0):
    """Relative pose error per metre over ``delta`` metres of true path (module docstring)."""
    true_poses = np.asarray(true_poses, dtype=float)
    estimates = np.asarray(estimates, dtype=float)
    pairs = path_pairs(true_poses[:, :2], delta)
    if not pairs:
        return RelativeError(float("nan"), float("nan"), 0)
    i, j = np.array(pairs).T
    true_motion = compose(inverse(true_poses[i]), true_poses[j])
    estimated_motion = compose(inverse(estimates[i]), estimates[j])
    error = compose(inverse(true_motion), estimated_motion)
    trans = np.linalg.norm(error[:, :2], axis=1)
    rot = np.degrees(np.abs(wrap_angle(error[:, 2])))
    return RelativeError(
        float(np.sqrt(np.mean(trans**2)) / delta),
        float(np.sqrt(np.mean(rot**2)) / delta),
        len(pairs),
    )


def pose_error(estimate: ArrayLike, true_pose: ArrayLike) -> np.ndarray:
    """``estimate - true_pose`` with the yaw difference wrapped to ``(-pi, pi]``."""
    error = np.asarray(estimate, dtype=float) - np.asarray(true_pose, dtype=float)
    error[..., 2] = wrap_angle(error[..., 2])
    return error


def nees(errors: ArrayLike, covariances: ArrayLike) -> np.ndarray:
    """Normalised estimation error squared of each error ``(N, d)`` and covariance
    ``(N, d, d)`` (also the NIS, given innovations and their covariances)."""
    errors = np.asarray(errors, dtype=float)
    covariances = np.asarray(covariances, dtype=float)
    solved = np.linalg.solve(covariances, errors[..., None])[..., 0]
    return np.einsum("...i,...i->...", errors, solved)


def chi2_bounds(dof: int, runs: float = 1, probability: float = BOUNDS_PROBABILITY):
    """Two-sided bounds of the mean of ``runs`` chi-square values of ``dof`` degrees of
    freedom: ``chi2.ppf([a, 1 - a], runs * dof) / runs`` with ``a = (1 - probability) / 2``
    (``runs`` may be an effective, fractional count of independent values)."""
    if dof < 1 or runs < 1:
        raise ValueError(f"dof and runs must be at least 1, got {dof} and {runs}")
    from scipy.stats import chi2  # here: SciPy's stats take seconds to load in each worker

    tail = (1.0 - probability) / 2.0
    lo, hi = chi2.ppf([tail, 1.0 - tail], runs * dof) / runs
    return float(lo), float(hi)


def autocorrelation_time(series: ArrayLike) -> float:
    """Integrated autocorrelation time ``tau = 1 + 2 sum_k rho(k)`` of a series (Sokal; the
    sum stops at the first lag whose autocorrelation is not positive, Geyer's initial
    positive sequence): ``N / tau`` of its ``N`` values are worth independent ones for the
    variance of their mean. 1 for a white series, at most ``N``."""
    values = np.asarray(series, dtype=float)
    values = values - values.mean()
    n = len(values)
    variance = float(values @ values)
    if n < 2 or variance == 0.0:
        return 1.0
    spectrum = np.fft.rfft(values, 2 * n)
    rho = np.fft.irfft(spectrum * np.conj(spectrum))[:n] / variance
    positive = np.argmax(rho[1:] <= 0) if np.any(rho[1:] <= 0) else n - 1
    return float(min(n, max(1.0, 1.0 + 2.0 * rho[1 : 1 + positive].sum())))


def time_averaged_nees_bounds(
    average_trace: ArrayLike, dof: int, runs: int, probability: float = BOUNDS_PROBABILITY
) -> tuple[float, tuple[float, float], float]:
    """The time average of Bar-Shalom's Monte-Carlo NEES and its own two-sided bounds.

    ``average_trace`` is the NEES averaged over ``runs`` independent runs at each of its ``K``
    steps (``runs`` times it is chi-square with ``runs * dof`` degrees of freedom for a
    consistent estimator, Bar-Shalom, Li and Kirubarajan 2001, sect. 5.4). Its time average
    would be chi-square with ``runs * K * dof`` degrees of freedom if the steps were
    independent; they are not (an estimation error persists over many steps), so ``K`` is
    replaced by the effective number of independent steps ``K / tau``
    (:func:`autocorrelation_time` of the trace). Returns the average, its bounds
    ``chi2_bounds(dof, runs * K / tau)`` and ``K / tau``.
    """
    trace = np.asarray(average_trace, dtype=float)
    effective_steps = len(trace) / autocorrelation_time(trace)
    return (
        float(trace.mean()),
        chi2_bounds(dof, runs * effective_steps, probability),
        effective_steps,
    )


def fraction_inside(values: ArrayLike, bounds: tuple[float, float]) -> float:
    """Fraction of ``values`` within ``bounds`` (inclusive); NaN for no values."""
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return float("nan")
    return float(np.mean((values >= bounds[0]) & (values <= bounds[1])))


def distance_to_path(points: ArrayLike, path: ArrayLike) -> np.ndarray:
    """Distance (m) of each point ``(N, 2)`` to the polyline ``path`` ``(K, 2)``."""
    points = np.asarray(points, dtype=float)[:, None, :]
    a, b = np.asarray(path, dtype=float)[:-1], np.asarray(path, dtype=float)[1:]
    ab = b - a
    t = np.clip(np.sum((points - a) * ab, axis=-1) / np.sum(ab * ab, axis=-1), 0.0, 1.0)
    nearest = a + t[..., None] * ab
    return np.min(np.linalg.norm(points - nearest, axis=-1), axis=1)
