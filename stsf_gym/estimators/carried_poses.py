"""Robot poses carried from earlier landmark frames, correlated with the estimate they update.

A landmark frame ``j`` gives the robot's pose through the landmark's map pose. Carried to now
by the odometry since (eq. 3: ``r_j = map (+) (-) TS(j)`` is the pose at frame ``j`` composed
with the odometry from ``j`` to now), it is a *carried pose* with error ``eps_j``. STSF fuses
the carried poses of a track, ``r = sum_j P_j r_j`` (eq. 2), and merges ``r`` with the estimate
(eq. 23-24). Eq. 23-24 assume the two independent; they are not:

- frames already merged into the estimate are merged again: the estimate's error ``e`` holds
  ``eps_j`` through the earlier gains;
- the odometry since frame ``j`` moved both ``r_j`` and the estimate: the same wheel error is
  in both, and cancels in their difference.

This class keeps what that needs, to first order: ``X = Cov(e, eps)`` and ``Y = Cov(eps, eps)``
for every carried pose (the estimate's own ``P`` stays with the estimator).

**Prediction.** The estimate and every carried pose move by the same odometry increment, the
estimate as ``e <- F e + G du`` (``Q = G N G^T``); the carried poses lie within centimetres of
the estimate, so the same ``F`` serves for all, and ``du`` is shared::

    X <- F X F^T + Q,    Y <- F Y F^T + Q   (each 3x3 block)

**A new frame** adds ``eps_new`` with its measurement covariance, independent of the rest.

**Merge** of ``r = h eps`` (``h = [P_1 I, ..., P_k I]`` over the track's poses, zero elsewhere)
with the estimate. The innovation ``nu = r - x`` has the error ``h eps - e``, so::

    S = P + h Y h^T - X h^T - h X^T          (innovation covariance, used by the gate)
    K = (P - X h^T) S^-1                     (eq. 24 with the cross-covariance)
    e <- (I - K) e + K h eps = T [e; eps],   T = [I - K, K h]
    P <- T [[P, X], [X^T, Y]] T^T,           X <- (I - K) X + K h Y

``Y`` is unchanged: a merge changes the estimate, not the frames. With ``X = 0`` and one pose
this is eq. 23-24 exactly (the conventional fusion); with a long track it counts each frame's
information once, so the merged covariance is neither over-confident (a plain merge of the
fused track) nor needlessly wide (covariance intersection).
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping

import numpy as np


class CarriedPoses:
    """Cross-covariances of carried poses with the estimate, keyed by frame."""

    def __init__(self) -> None:
        self.clear()

    def clear(self) -> None:
        """Forget every carried pose."""
        self.keys: list[Hashable] = []
        self.cross = np.zeros((3, 0))  # X = Cov(e, eps)
        self.joint = np.zeros((0, 0))  # Y = Cov(eps, eps)

    def predict(self, F: np.ndarray, Q: np.ndarray) -> None:
        """Move every carried pose with the estimate: ``e <- F e + G du``, ``Q = G N G^T``."""
        n = len(self.keys)
        if not n:
            return
        blocks = self.joint.reshape(n, 3, n, 3)
        self.joint = np.einsum("ab,ibjc,dc->iajd", F, blocks, F).reshape(3 * n, 3 * n)
        self.joint += np.tile(Q, (n, n))
        self.cross = np.einsum("ab,bjc,dc->ajd", F, self.cross.reshape(3, n, 3), F)
        self.cross = self.cross.reshape(3, 3 * n) + np.tile(Q, (1, n))

    def add(self, key: Hashable, cov: np.ndarray) -> None:
        """A new carried pose with error covariance ``cov``, independent of everything else."""
        if key in self.keys:
            raise ValueError(f"carried pose {key!r} exists already")
        n = len(self.keys)
        joint = np.zeros((3 * n + 3, 3 * n + 3))
        joint[: 3 * n, : 3 * n] = self.joint
        joint[3 * n :, 3 * n :] = cov
        self.keys.append(key)
        self.joint = joint
        self.cross = np.hstack([self.cross, np.zeros((3, 3))])

    def remove(self, keys) -> None:
        """Forget the carried poses ``keys`` (those not held are ignored)."""
        gone = set(keys)
        kept = [i for i, key in enumerate(self.keys) if key not in gone]
        columns = (3 * np.asarray(kept, dtype=int)[:, None] + np.arange(3)).ravel()
        self.keys = [self.keys[i] for i in kept]
        self.joint = self.joint[np.ix_(columns, columns)]
        self.cross = self.cross[:, columns]

    def merge(
        self, P: np.ndarray, weights: Mapping[Hashable, float], innovation: np.ndarray, gate: float
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """Merge ``r = sum_j weights[j] r_j`` with the estimate (covariance ``P``).

        ``innovation`` is ``r - x`` (angle wrapped). Returns the correction ``dx`` and the new
        ``P``, or ``None`` when the squared Mahalanobis distance under ``S`` exceeds ``gate``
        (nothing changes then).
        """
        h = np.zeros((3, 3 * len(self.keys)))
        for key, weight in weights.items():
            i = self.keys.index(key)
            h[:, 3 * i : 3 * i + 3] = weight * np.eye(3)
        xh = self.cross @ h.T
        S = P + h @ self.joint @ h.T - xh - xh.T
        S = 0.5 * (S + S.T)
        try:
            chol = np.linalg.cholesky(S)
        except np.linalg.LinAlgError:
            return None
        whitened = np.linalg.solve(chol, innovation)
        if whitened @ whitened > gate:
            return None
        K = np.linalg.solve(S, (P - xh).T).T
        T = np.hstack([np.eye(3) - K, K @ h])
        stacked = np.vstack([self.cross, self.joint])  # Cov([e; eps], eps)
        full = np.hstack([np.vstack([P, self.cross.T]), stacked])
        P_new = T @ full @ T.T
        self.cross = T @ stacked
        return K @ innovation, 0.5 * (P_new + P_new.T)
