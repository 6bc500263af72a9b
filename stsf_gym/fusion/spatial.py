"""Conventional (spatial) sensor fusion, eq. 1 of the paper.

``n`` sensors each give an ``m``-dimensional measurement ``x_i`` of the same
quantity at the same instant; the fused value is the weighted sum
``x_hat = sum_i W_i x_i`` with ``sum_i W_i = I`` so that it stays unbiased.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]

_SUM_TOL = 1e-9


def inverse_variance_weights(covs: ArrayLike) -> Array:
    """Minimum-variance weights ``W_i = (sum_j C_j^-1)^-1 C_i^-1`` for eq. 1.

    ``covs`` has shape ``(n, m, m)``; the result has the same shape and sums to ``I``.
    """
    covs = np.asarray(covs, dtype=float)
    eye = np.broadcast_to(np.eye(covs.shape[-1]), covs.shape)
    informations = np.linalg.solve(covs, eye)  # C_i^-1
    return np.linalg.solve(informations.sum(axis=0), informations)


def _as_weight_matrices(weights: ArrayLike, n: int, m: int) -> Array:
    """Check the weights of eq. 1 and return them as ``(n, m, m)`` matrices."""
    w = np.asarray(weights, dtype=float)
    if w.shape == (n,):
        if abs(w.sum() - 1.0) > _SUM_TOL:
            raise ValueError(f"scalar weights must sum to 1 (eq. 1), they sum to {w.sum():.12g}")
        return w[:, None, None] * np.eye(m)
    if w.shape == (n, m, m):
        err = np.abs(w.sum(axis=0) - np.eye(m)).max()
        if err > _SUM_TOL:
            raise ValueError(
                f"weight matrices must sum to the identity (eq. 1); largest deviation {err:.3g}"
            )
        return w
    raise ValueError(f"weights must have shape ({n},) or ({n}, {m}, {m}), got {w.shape}")


def spatial_fusion(
    xs: ArrayLike, weights: ArrayLike | None = None, covs: ArrayLike | None = None
) -> tuple[Array, Array | None]:
    """Fuse simultaneous measurements by eq. 1, ``x_hat = sum_i W_i x_i``.

    Args:
        xs: measurements ``x_i``, shape ``(n, m)``.
        weights: ``None``, ``n`` scalars summing to 1, or ``n`` matrices ``(n, m, m)``
            summing to the identity.
        covs: covariances ``C_i`` of the (independent) measurements, ``(n, m, m)``.
            Without ``weights`` they select the inverse-variance weights
            (:func:`inverse_variance_weights`), the minimum-variance linear estimate.

    Returns:
        ``(x_hat, C)``: ``C = sum_i W_i C_i W_i^T`` when ``covs`` is given, else ``None``.
        Without weights and covariances all sensors get the weight ``1/n``.
    """
    xs = np.asarray(xs, dtype=float)
    if xs.ndim != 2 or xs.shape[0] == 0:
        raise ValueError(f"xs must have shape (n, m) with n >= 1, got {xs.shape}")
    n, m = xs.shape
    if covs is not None:
        covs = np.asarray(covs, dtype=float)
        if covs.shape != (n, m, m):
            raise ValueError(f"covs must have shape ({n}, {m}, {m}), got {covs.shape}")
    if weights is not None:
        w = _as_weight_matrices(weights, n, m)
    elif covs is not None:
        w = inverse_variance_weights(covs)
    else:
        w = np.full(n, 1.0 / n)[:, None, None] * np.eye(m)
    x_hat = np.einsum("iab,ib->a", w, xs)
    if covs is None:
        return x_hat, None
    cov = np.einsum("iab,ibc,idc->ad", w, covs, w)
    return x_hat, 0.5 * (cov + cov.T)
