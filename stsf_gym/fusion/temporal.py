"""STSF temporal fusion of transformed measurement sets, eq. 2, 4 and 5.

Input: the ``k`` sets of one track already transformed into the current frame,
``TS(j)`` for ``j = 1..k`` (eq. 3; ``stsf_gym.fusion.track`` builds them), stacked as
``ts`` of shape ``(k, m)`` with the last row the current set, and their *joint*
covariance ``sigma``: a ``(k m, k m)`` matrix, or the factored
:class:`~stsf_gym.fusion.covariance.TrackCovariance` a track produces (same result,
``O(k)`` instead of ``O(k^2)`` work outside GLS). One sensor is fused at a time, so
eq. 2 reads ``x_hat = sum_j W_j TS(j)`` with ``sum_j W_j = I``.

Correlation and over-confidence. ``TS(j)`` for different ``j`` are carried into the
current frame by the *same* odometry increments, so their errors are correlated:
averaging ``k`` sets does not divide the odometry error by ``k``. The fused
covariance is therefore always ``W sigma W^T`` with the full joint ``sigma``; it
never assumes the sets independent, so re-using old frames cannot make the result
over-confident: to first order this is exact for any fixed weights (and the
significance weights are constant for sets inside their gate).

Weights, selected by ``method``:

* ``"significance"`` (the paper): ``W_j = P_j I`` with ``P_j`` from eq. 4-5, see
  :func:`significance`.
* ``"gls"``: generalised least squares with the joint covariance,
  ``W = (E^T sigma^-1 E)^-1 E^T sigma^-1`` (``E``: ``k`` stacked identities), the best
  linear unbiased estimate; its covariance is ``(E^T sigma^-1 E)^-1``.

Angles (``angle_index``) are averaged as offsets from the current set's value,
wrapped to ``(-pi, pi]``, so a track straddling ``+-pi`` fuses correctly.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stsf_gym.fusion.chi_square import chi_square_quantile
from stsf_gym.fusion.covariance import DenseCovariance, TrackCovariance
from stsf_gym.geometry import wrap_angle

Array = NDArray[np.float64]
Method = Literal["significance", "gls"]
JointCovariance = DenseCovariance | TrackCovariance


class STSFResult(NamedTuple):
    """Fused measurement ``x`` (m,), its covariance ``cov`` (m, m), weights ``W_j`` (k, m, m)."""

    x: Array
    cov: Array
    weights: Array


def _prepare(
    ts: ArrayLike, sigma: ArrayLike | JointCovariance, angle_index: Sequence[int]
) -> tuple[Array, Array, JointCovariance]:
    """Check shapes; return ``ts``, the offsets ``TS(j) - TS(k)`` (angles wrapped), ``sigma``."""
    ts = np.asarray(ts, dtype=float)
    ts = ts[:, None] if ts.ndim == 1 else ts
    if ts.ndim != 2 or ts.shape[0] == 0:
        raise ValueError(f"ts must have shape (k, m) or (k,) with k >= 1, got {ts.shape}")
    k, m = ts.shape
    if not isinstance(sigma, (DenseCovariance, TrackCovariance)):
        sigma = DenseCovariance(np.atleast_2d(np.asarray(sigma, dtype=float)), k, m)
        if sigma.matrix.shape != (k * m, k * m):
            raise ValueError(f"sigma must have shape ({k * m}, {k * m}) for ts {ts.shape}")
    elif (sigma.k, sigma.m) != (k, m):
        raise ValueError(f"sigma describes {sigma.k} sets of size {sigma.m}, ts is {ts.shape}")
    offsets = ts - ts[-1]
    angles = list(angle_index)
    offsets[:, angles] = wrap_angle(offsets[:, angles])
    return ts, offsets, sigma


def _significance(offsets: Array, marginals: Array, gate: float | None) -> Array:
    m = offsets.shape[1]
    if gate is None:
        gate = chi_square_quantile(0.99, m)
    pair = marginals + marginals[-1]
    d2 = np.einsum("ja,ja->j", offsets, np.linalg.solve(pair, offsets[..., None])[..., 0])
    _, logdet = np.linalg.slogdet(marginals)
    log_psi = -0.5 * np.maximum(d2 - gate, 0.0) - logdet / m
    psi = np.exp(log_psi - log_psi.max())
    return psi / psi.sum()


def significance(
    ts: ArrayLike,
    sigma: ArrayLike | JointCovariance,
    angle_index: Sequence[int] = (),
    gate: float | None = None,
) -> Array:
    """Significance ``P_j`` of each set, eq. 4-5 (our reading, below).

    Eq. 4 correlates the track with itself. Read literally on raw vectors it is
    unit-dependent and almost the same for every set of one landmark, so it cannot
    tell an outlier. We read it on the Gaussian densities of the sets (sect. 3.3)
    and split it, like Fig. 2, into "verify the significance" and "adjust weight":

        Psi_j = rho_j * |sigma_jj|^(-1/m)

    * ``rho_j``, the correlation of set ``j`` with the current set ``k``: with the
      Mahalanobis distance ``d_j^2`` of ``TS(j) - TS(k)`` under
      ``sigma_jj + sigma_kk`` (exactly the covariance of the difference, as the
      current set carries no odometry error), ``rho_j = exp(-(d_j^2 - gate)_+ / 2)``.
      Sets consistent with the current one (``d_j^2 <= gate``, by default the 99 %
      chi-square quantile with ``m`` degrees of freedom) are the same data,
      significance 1; beyond the gate ``rho_j`` falls like the correlation of two
      Gaussian densities, towards 0. ``gate=0`` gives that correlation throughout.
    * ``|sigma_jj|^(-1/m)``, the zero-lag term: the set's precision as a scalar
      (geometric mean of the inverse variances), so sets made uncertain by a long
      odometry chain count less. Constant unit changes cancel in eq. 5.

    ``P_j = Psi_j / sum_j Psi_j`` (eq. 5), so ``P_j >= 0`` and ``sum P_j = 1``. Computed
    in log space: distant outliers get 0, never NaN. The current set is the
    reference; if it is itself the outlier, the older sets are the ones rejected.
    """
    _, offsets, sigma = _prepare(ts, sigma, angle_index)
    return _significance(offsets, sigma.marginals(), gate)


def _gls_weights(sigma: Array, k: int, m: int) -> Array:
    """``W = (E^T sigma^-1 E)^-1 E^T sigma^-1`` as ``(k, m, m)`` blocks."""
    try:
        np.linalg.cholesky(sigma)  # the test of positive definiteness
    except np.linalg.LinAlgError as err:
        raise ValueError("the joint covariance must be positive definite for GLS") from err
    g = np.linalg.solve(sigma, np.tile(np.eye(m), (k, 1))).reshape(k, m, m)  # sigma^-1 E
    information = g.sum(axis=0)  # E^T sigma^-1 E
    return np.linalg.solve(information, np.swapaxes(g, 1, 2))


def stsf_fuse(
    ts: ArrayLike,
    sigma: ArrayLike | JointCovariance,
    method: Method = "significance",
    angle_index: Sequence[int] = (),
    gate: float | None = None,
) -> STSFResult:
    """Fuse the transformed sets of one track, eq. 2: ``x_hat = sum_j W_j TS(j)``.

    Args:
        ts: ``TS(j)``, shape ``(k, m)`` (or ``(k,)`` for scalars), current set last.
        sigma: their joint covariance, a ``(k m, k m)`` matrix (row blocks in the order
            of ``ts``) or a :class:`~stsf_gym.fusion.covariance.TrackCovariance`.
        method: ``"significance"`` (eq. 4-5) or ``"gls"`` (best linear unbiased).
        angle_index: entries of the measurement vector that are angles.
        gate: chi-square gate of :func:`significance` (default: 99 % quantile).

    Returns:
        :class:`STSFResult` with ``cov = W sigma W^T`` (never assumes independence).
        A single set (``k = 1``) is returned unchanged.
    """
    ts, offsets, sigma = _prepare(ts, sigma, angle_index)
    k, m = ts.shape
    if method == "significance":
        weights = _significance(offsets, sigma.marginals(), gate)[:, None, None] * np.eye(m)
    elif method == "gls":
        weights = _gls_weights(sigma.dense(), k, m)
    else:
        raise ValueError(f"method must be 'significance' or 'gls', got {method!r}")
    x = ts[-1] + np.einsum("jab,jb->a", weights, offsets)
    angles = list(angle_index)
    x[angles] = wrap_angle(x[angles])
    cov = sigma.transform(weights)
    return STSFResult(x, 0.5 * (cov + cov.T), weights)
