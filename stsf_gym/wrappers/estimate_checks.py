"""The check every estimate passes before an agent sees it: three finite numbers and a
symmetric positive definite 3x3 covariance, or an :class:`EstimateError` naming the source."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


class EstimateError(ValueError):
    """A pose source returned what no pose estimate can be: a pose that is not three finite
    numbers, or a covariance that is not a symmetric positive definite 3x3 matrix."""


#: How far a covariance may be from symmetric, relative to its largest entry (rounding).
SYMMETRY_TOLERANCE = 1e-6


def check_estimate(name: str, mean: Any, cov: Any) -> tuple[np.ndarray, np.ndarray]:
    """``mean`` and ``cov`` as float arrays if they are a pose estimate, else an
    :class:`EstimateError` naming pose source ``name`` (checked at every step it returns, on
    plain floats: a 3x3 check costs more in numpy's call overhead than in arithmetic)."""
    mean, cov = np.asarray(mean, dtype=float), np.asarray(cov, dtype=float)
    where = f"pose source {name!r} returned"
    if mean.shape != (3,) or not all(map(math.isfinite, mean.tolist())):
        raise EstimateError(f"{where} the pose {mean.tolist()}: not three finite numbers x, y, yaw")
    entries = cov.ravel().tolist()
    if cov.shape != (3, 3) or not all(map(math.isfinite, entries)):
        raise EstimateError(f"{where} the covariance {cov.tolist()}: not a finite 3x3 matrix")
    scale = max(map(abs, entries))
    asymmetry = max(abs(entries[i] - entries[j]) for i, j in ((1, 3), (2, 6), (5, 7)))
    if asymmetry > SYMMETRY_TOLERANCE * scale:
        raise EstimateError(f"{where} the covariance {cov.tolist()}: not symmetric")
    if not _cholesky_succeeds(entries):
        eigenvalues = np.linalg.eigvalsh(cov).tolist()
        raise EstimateError(
            f"{where} the covariance {cov.tolist()}: not positive definite (eigenvalues "
            f"{eigenvalues}); NEES and the agent's uncertainty need a positive definite one"
        )
    return mean, cov


def _cholesky_succeeds(c: list[float]) -> bool:
    """Whether the Cholesky factorization ``L L^T`` of the symmetric 3x3 matrix ``c`` (row
    major; its lower triangle read, as ``np.linalg.cholesky`` does) exists: every pivot > 0."""
    if not c[0] > 0:
        return False
    l00 = math.sqrt(c[0])
    l10, l20 = c[3] / l00, c[6] / l00
    pivot = c[4] - l10 * l10
    if not pivot > 0:
        return False
    l21 = (c[7] - l20 * l10) / math.sqrt(pivot)
    return c[8] - l20 * l20 - l21 * l21 > 0
