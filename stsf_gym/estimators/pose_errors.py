"""The joint covariance of a pose estimate's error and what it is correlated with.

Three kinds of error, to first order, stacked as ``y = [e; c; eps_1; ...; eps_n]``:

- ``e``: the estimate's error (3: x, y, yaw); its covariance is the estimator's ``P``;
- ``c``: the odometry calibration errors (3: relative left and right wheel radius, relative
  wheelbase), one draw per episode that the robot cannot know, and for a camera the error of
  its mount's position on the robot (2: x, y) and of its believed calibration (2: the
  principal point as a heading, the focal length as a depth scale), the same in every
  frame. They are
  *considered*, not estimated (a Schmidt filter): ``Cov(c)`` never changes, but every error
  they drive stays correlated with them. Dead reckoning's error then grows linearly with
  distance, as a fixed scale error makes it, instead of a random walk's square root; the
  drift between two landmark sightings is neither overstated on a short gap nor understated
  on a long one, and a mount or calibration error is not averaged away over many frames;
- ``eps_j``: *carried poses*, the robot pose an earlier landmark frame ``j`` gives, carried to
  now by the odometry since (eq. 3: ``map (+) (-) TS(j)``), which STSF fuses (eq. 2) and
  merges with the estimate (eq. 23-24). They share the odometry since frame ``j`` with ``e``,
  their motion-stereo baselines depend on ``c``, and frames merged before are in ``e``
  already: a merge that ignored this would count them again and again.

**Prediction.** The estimate and every carried pose move by the same wheel travel, with
Jacobians ``F`` (pose), ``G`` (wheel travels, slip ``N``) and ``G_c`` (calibration)::

    e <- F e + G_c c + G w,   eps_j <- F eps_j + G_c c + G w,   c <- c

(the carried poses lie within centimetres of the estimate: one ``F`` serves all).

**Updates** are ``e <- e + K nu`` with an innovation whose error is linear in ``y`` plus
independent noise ``v`` (covariance ``R``): ``nu = L y + v``. Then ``S = L Y L^T + R``, the
gain is ``K = -Cov(e, nu) S^-1`` and ``Y <- T Y T^T + K R K^T`` on the ``e`` block, with ``T``
the identity plus ``K L`` in the rows of ``e`` (the Joseph form, for the whole ``y``):

- an EKF measurement ``z = h(x) + v``: ``L = [-H, 0, 0]``, ``K = P H^T S^-1``;
- a fused track ``r = sum_j W_j r_j``: ``L = [-I, 0, W_1 ... W_n]``, ``R = 0``. With ``c``
  left out and one independent pose this is eq. 23-24 exactly (the conventional filter).

**Replacement** (the paper's conventional fusion): the estimate becomes a measured pose whose
error is ``v + M c`` (``v`` independent, covariance ``R``); the innovation ``r - x`` is only
tested (``L = [-I, M, 0]``), then ``e``'s rows and columns are replaced, the carried poses
dropped: nothing of the earlier estimate is kept.
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping

import numpy as np

POSE = slice(0, 3)
AXES = np.arange(3)  # x, y, yaw: the three rows of a pose


class PoseErrors:
    """``Cov([e; c; eps_1 ... eps_n])``; :attr:`P` is the estimate's covariance."""

    def __init__(self, cov: np.ndarray, considered_cov: np.ndarray) -> None:
        k = len(considered_cov)
        self.considered, self.first_pose = slice(3, 3 + k), 3 + k
        self.joint = np.zeros((3 + k, 3 + k))
        self.joint[self.considered, self.considered] = considered_cov
        self.keys: list[Hashable] = []
        self._predictions: dict[int, tuple[np.ndarray, ...]] = {}  # by size, :meth:`_prediction`
        #: ``(nu^T S^-1 nu, len(nu))`` of every innovation tested, gated out or not (NIS).
        self.nis: list[tuple[float, int]] = []
        self.restart(cov)

    @property
    def P(self) -> np.ndarray:
        return self.joint[POSE, POSE].copy()

    def restart(self, cov: np.ndarray) -> None:
        """A new estimate with covariance ``cov``, independent of everything (a re-localisation);
        the carried poses are dropped."""
        self.remove(list(self.keys))
        self.joint[POSE, :] = 0.0
        self.joint[:, POSE] = 0.0
        self.joint[POSE, POSE] = cov

    def _pose_rows(self, i: int) -> slice:
        start = self.first_pose + 3 * i
        return slice(start, start + 3)

    def _considered(self, jacobian: np.ndarray) -> np.ndarray:
        """A Jacobian by the first considered parameters, zero-padded to all of them."""
        padded = np.zeros((len(jacobian), self.considered.stop - 3))
        padded[:, : jacobian.shape[1]] = jacobian
        return padded

    def predict(self, F: np.ndarray, Q: np.ndarray, G_c: np.ndarray) -> None:
        """One odometry step: ``F``, slip noise ``Q = G N G^T`` and calibration Jacobian ``G_c``."""
        T, B, rows, by_calibration = self._prediction(len(self.joint))
        T[rows, rows.transpose(0, 2, 1)] = F
        T[rows, by_calibration[: G_c.shape[1]]] = G_c
        joint = T @ self.joint @ T.T + B @ Q @ B.T
        self.joint = 0.5 * (joint + joint.T)

    def _prediction(self, size: int) -> tuple[np.ndarray, ...]:
        """For a joint of ``size``: ``T`` (the identity, its ``F`` and ``G_c`` blocks rewritten
        by every prediction, the zero padding of ``G_c`` to all considered parameters kept),
        ``B`` (the identity in the rows of ``e`` and of every ``eps_j``), those rows as
        (pose, 3, 1) index blocks, and the considered parameters' columns; made once a size."""
        if size not in self._predictions:
            starts = np.array([0, *range(self.first_pose, size, 3)])
            rows = starts[:, None, None] + AXES[:, None]
            B = np.zeros((size, 3))
            B[rows, AXES] = np.eye(3)
            by_calibration = np.arange(self.considered.start, self.considered.stop)
            self._predictions[size] = (np.eye(size), B, rows, by_calibration)
        return self._predictions[size]

    def add(self, key: Hashable, cov: np.ndarray, by_considered: np.ndarray) -> None:
        """A carried pose whose error is independent noise (``cov``) plus
        ``by_considered @ c``."""
        if key in self.keys:
            raise ValueError(f"carried pose {key!r} exists already")
        M = self._considered(by_considered)
        row = M @ self.joint[self.considered, :]
        size = len(self.joint)
        joint = np.zeros((size + 3, size + 3))
        joint[:size, :size] = self.joint
        joint[size:, :size], joint[:size, size:] = row, row.T
        joint[size:, size:] = cov + M @ self.joint[self.considered, self.considered] @ M.T
        self.joint = joint
        self.keys.append(key)

    def remove(self, keys) -> None:
        """Forget the carried poses ``keys`` (those not held are ignored)."""
        gone = set(keys)
        kept = list(range(self.first_pose)) + [
            index
            for i, key in enumerate(self.keys)
            if key not in gone
            for index in range(self.first_pose + 3 * i, self.first_pose + 3 * i + 3)
        ]
        self.keys = [key for key in self.keys if key not in gone]
        self.joint = self.joint[np.ix_(kept, kept)]

    def correct(
        self,
        H: np.ndarray,
        R: np.ndarray,
        innovation: np.ndarray,
        gate: float,
        by_considered: np.ndarray | None = None,
    ) -> np.ndarray | None:
        """EKF update with ``z - h(x)`` = ``innovation``, ``H = dh/dx``, noise ``R`` and
        ``by_considered``, the measurement's Jacobian by ``c``: the correction to add to the
        estimate, or ``None`` when gated out (nothing changes)."""
        L = np.zeros((len(H), len(self.joint)))
        L[:, POSE] = -H
        if by_considered is not None:
            L[:, self.considered] = self._considered(by_considered)
        return self._update(L, R, innovation, gate)

    def merge(
        self, weights: Mapping[Hashable, np.ndarray], innovation: np.ndarray, gate: float
    ) -> np.ndarray | None:
        """Merge ``r = sum_j weights[j] r_j`` with the estimate; ``innovation = r - x``."""
        L = np.zeros((3, len(self.joint)))
        L[:, POSE] = -np.eye(3)
        for key, weight in weights.items():
            L[:, self._pose_rows(self.keys.index(key))] = weight
        return self._update(L, np.zeros((3, 3)), innovation, gate)

    def replace(
        self, cov: np.ndarray, by_considered: np.ndarray, innovation: np.ndarray, gate: float
    ) -> bool:
        """Make the estimate a measured pose (independent covariance ``cov``, Jacobian
        ``by_considered`` by ``c``; ``innovation`` = measured - estimate), unless gated out
        (then nothing changes and ``False`` is returned)."""
        M = self._considered(by_considered)
        L = np.zeros((3, len(self.joint)))
        L[:, POSE], L[:, self.considered] = -np.eye(3), M
        S = L @ self.joint @ L.T + cov
        try:
            whitened = np.linalg.solve(np.linalg.cholesky(0.5 * (S + S.T)), innovation)
        except np.linalg.LinAlgError:
            return False
        self.nis.append((float(whitened @ whitened), len(innovation)))
        if not whitened @ whitened <= gate:  # also rejects NaN
            return False
        self.restart(cov + M @ self.joint[self.considered, self.considered] @ M.T)
        self.joint[POSE, self.considered] = M @ self.joint[self.considered, self.considered]
        self.joint[self.considered, POSE] = self.joint[POSE, self.considered].T
        return True

    def _update(
        self, L: np.ndarray, R: np.ndarray, innovation: np.ndarray, gate: float
    ) -> np.ndarray | None:
        S = L @ self.joint @ L.T + R
        S = 0.5 * (S + S.T)
        try:
            chol = np.linalg.cholesky(S)
        except np.linalg.LinAlgError:
            return None
        whitened = np.linalg.solve(chol, innovation)
        self.nis.append((float(whitened @ whitened), len(innovation)))
        if not whitened @ whitened <= gate:  # also rejects NaN
            return None
        K = -np.linalg.solve(S, L @ self.joint[:, POSE]).T  # -Cov(e, nu) S^-1
        T = np.eye(len(self.joint))
        T[POSE] += K @ L
        joint = T @ self.joint @ T.T
        joint[POSE, POSE] += K @ R @ K.T
        self.joint = 0.5 * (joint + joint.T)
        return K @ innovation
