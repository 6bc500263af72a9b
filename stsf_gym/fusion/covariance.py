"""Joint covariance of the ``k`` transformed sets ``TS(j)`` of one track.

STSF fuses ``x_hat = sum_j W_j TS(j)`` and needs three things of the joint
covariance ``sigma`` (``k m x k m``): the marginal blocks ``sigma_jj`` (significance,
eq. 4-5), the fused covariance ``W sigma W^T`` and, for generalised least squares,
``sigma`` itself. :class:`DenseCovariance` holds any ``sigma``;
:class:`TrackCovariance` holds the factored form that odometry produces (see
``stsf_gym.fusion.track``),

    sigma_jl = delta_jl M_j + H_j S_max(j, l) H_l^T,   S_j = sum_{i >= j} Gamma_i,

and gives marginals and ``W sigma W^T`` in ``O(k)``: ``S_max(j, l)`` contains
``Gamma_i`` exactly when ``j <= i`` and ``l <= i``, so

    W sigma W^T = sum_j W_j M_j W_j^T + sum_i N_i Gamma_i N_i^T,   N_i = sum_{j <= i} W_j H_j.

The second sum is why re-used frames do not make the result over-confident: the
odometry error ``Gamma_i`` enters once, through the summed weights ``N_i`` of all
frames it affects, not once per frame.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def _sandwich(weights: Array, covs: Array) -> Array:
    """``sum_j W_j C_j W_j^T`` for stacks ``(k, p, m)`` and ``(k, m, m)``."""
    return (weights @ covs @ np.swapaxes(weights, -1, -2)).sum(axis=0)


class DenseCovariance(NamedTuple):
    """Any joint covariance ``sigma`` of ``k`` sets of dimension ``m``, as a matrix."""

    matrix: Array  # (k m, k m)
    k: int
    m: int

    def marginals(self) -> Array:
        """The diagonal blocks ``sigma_jj``, ``(k, m, m)``."""
        blocks = self.matrix.reshape(self.k, self.m, self.k, self.m)
        return blocks[np.arange(self.k), :, np.arange(self.k), :]

    def dense(self) -> Array:
        """The matrix itself."""
        return self.matrix

    def transform(self, weights: Array) -> Array:
        """``W sigma W^T`` for weights ``W_j`` stacked as ``(k, p, m)``."""
        row = np.swapaxes(weights, 0, 1).reshape(weights.shape[1], self.k * self.m)
        return row @ self.matrix @ row.T


class TrackCovariance(NamedTuple):
    """The factored joint covariance of a track (module docstring)."""

    meas: Array  # M_j, (k, m, m): measurement error carried into the current frame
    h: Array  # H_j, (k, m, m): how TS(j) moves under a shared odometry error
    gammas: Array  # Gamma_i, (k-1, m, m): odometry error of increment i, twist coordinates

    @property
    def k(self) -> int:
        return self.meas.shape[0]

    @property
    def m(self) -> int:
        return self.meas.shape[1]

    def suffix(self) -> Array:
        """``S_j = sum_{i >= j} Gamma_i``, ``(k, m, m)``, with ``S_k = 0``."""
        s = np.zeros_like(self.meas)
        s[:-1] = np.cumsum(self.gammas[::-1], axis=0)[::-1]
        return s

    def marginals(self) -> Array:
        """The diagonal blocks ``sigma_jj = M_j + H_j S_j H_j^T``, ``(k, m, m)``."""
        return self.meas + self.h @ self.suffix() @ np.swapaxes(self.h, -1, -2)

    def dense(self) -> Array:
        """The full ``(k m, k m)`` matrix, built from two rank-``m`` products."""
        k, m = self.k, self.m
        s, h_t = self.suffix(), np.swapaxes(self.h, -1, -2)
        upper = self.h.reshape(k * m, m) @ (s @ h_t).transpose(1, 0, 2).reshape(m, k * m)
        lower = (self.h @ s).reshape(k * m, m) @ h_t.transpose(1, 0, 2).reshape(m, k * m)
        block = np.repeat(np.arange(k), m)
        sigma = np.where(block[:, None] <= block[None, :], upper, lower)  # S_max(j, l)
        sigma.reshape(k, m, k, m)[np.arange(k), :, np.arange(k), :] += self.meas
        return 0.5 * (sigma + sigma.T)

    def transform(self, weights: Array) -> Array:
        """``W sigma W^T`` in ``O(k)`` (module docstring)."""
        prefix = np.cumsum(weights @ self.h, axis=0)[:-1]  # N_i for i < k
        return _sandwich(weights, self.meas) + _sandwich(prefix, self.gammas)
