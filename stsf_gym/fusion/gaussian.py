"""Gaussian observations and their merging (Smith & Cheeseman), eq. 21-24.

An observation is a mean ``X`` and a covariance ``C`` (sect. 3.3, Fig. 5). In
2-D it is often described by the standard deviations along its principal axes
and the direction ``theta`` of the major axis (eq. 21-22). Two observations of
the same quantity merge into one by the matrix form of the Kalman update
(eq. 23-24).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stsf_gym.geometry import rot2, wrap_angle

Array = NDArray[np.float64]


def covariance_from_axes(sigma_max: float, sigma_min: float, theta: float) -> Array:
    """Covariance of a 2-D observation from its principal axes, eq. 21-22.

    ``C = R(-theta)^T diag(sigma_max^2, sigma_min^2) R(-theta)``, where ``theta`` is the
    angle of the major axis to the global x axis, so the major eigenvector of ``C``
    is ``[cos(theta), sin(theta)]``.
    """
    if not 0.0 <= sigma_min <= sigma_max:
        raise ValueError(
            f"need 0 <= sigma_min <= sigma_max, got sigma_min={sigma_min}, sigma_max={sigma_max}"
        )
    canonical = np.diag([sigma_max**2, sigma_min**2])  # eq. 21
    rot = rot2(-theta)
    cov = rot.T @ canonical @ rot  # eq. 22
    return 0.5 * (cov + cov.T)


def merge_gaussians(
    x1: ArrayLike,
    C1: ArrayLike,
    x2: ArrayLike,
    C2: ArrayLike,
    angle_index: Sequence[int] = (),
) -> tuple[Array, Array]:
    """Merge two Gaussian observations of one quantity, eq. 23-24 (erratum applied).

    ``K = C1 (C1 + C2)^-1``, ``X = X1 + K (X2 - X1)`` (eq. 24 as corrected) and
    ``C = C1 - K C1`` (eq. 23), evaluated in the Joseph form
    ``(I - K) C1 (I - K)^T + K C2 K^T``, which equals eq. 23 but stays symmetric and
    positive semi-definite under rounding.

    Args:
        x1, C1: first mean ``(m,)`` and covariance ``(m, m)`` (scalars allowed for m = 1).
        x2, C2: second mean and covariance.
        angle_index: entries of ``x`` that are angles (e.g. ``[2]`` for a pose
            ``[x, y, theta]``): the innovation ``X2 - X1`` and the result are wrapped
            to ``(-pi, pi]``.
    """
    x1, x2 = np.atleast_1d(np.asarray(x1, float)), np.atleast_1d(np.asarray(x2, float))
    C1, C2 = np.atleast_2d(np.asarray(C1, float)), np.atleast_2d(np.asarray(C2, float))
    m = x1.shape[0]
    if x1.shape != (m,) or x2.shape != (m,) or C1.shape != (m, m) or C2.shape != (m, m):
        raise ValueError(
            f"shapes disagree: x1 {x1.shape}, C1 {C1.shape}, x2 {x2.shape}, C2 {C2.shape}"
        )
    angles = list(angle_index)
    innovation = x2 - x1
    innovation[angles] = wrap_angle(innovation[angles])
    gain = np.linalg.solve(C1 + C2, C1).T  # C1 (C1 + C2)^-1, both symmetric
    x = x1 + gain @ innovation
    x[angles] = wrap_angle(x[angles])
    rest = np.eye(m) - gain
    cov = rest @ C1 @ rest.T + gain @ C2 @ gain.T
    return x, 0.5 * (cov + cov.T)
