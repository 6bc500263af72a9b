"""Re-localisation: how a gated landmark estimator finds itself again after a kidnap.

The Mahalanobis gate rejects a landmark measurement that disagrees with the estimate: right
for a wrong detection, wrong when the estimate itself is off (the robot was carried away, or an
encoder spike turned its heading). Then every landmark is rejected and the estimator would stay
lost for good. Yet each rejected measurement of a map landmark gives the robot's full pose on
its own (the landmark's pose relative to the robot through its map pose,
:func:`~stsf_gym.estimators.landmark_observation.robot_pose_from_landmark`): a *candidate*.

- A candidate is kept with the estimate it disagreed with. While nothing is accepted the
  estimate moves by odometry only, so an earlier candidate is carried to now by the odometry
  since: ``candidate (+) ((-) mean_then (+) mean_now)``, its covariance by the Jacobian of that
  composition (the odometry's own noise over the short span is left out).
- A candidate's covariance is first order and leaves out the systematic errors (the mount's
  kinematics, the intrinsics), which PnP makes small but not nil: :data:`CANDIDATE_FLOOR_STD`
  is added to it.
- The last ``2 after - 1`` candidates are kept. When ``after`` of them, the newest included,
  agree with the newest (the chi-square ``gate`` on the sum of their covariances), the estimate
  is re-initialised at their information-weighted mean, carried to now (one PnP pose of a near
  or oblique board can be tens of centimetres off; the mean of the agreeing ones is not), with
  the newest one's covariance times ``inflation`` (their errors share the systematic part, so
  the mean is not trusted more than one of them). An odd outlier among them does not stop it.
  An accepted measurement clears the candidates.

A single wrong detection is one candidate that the following ones contradict, so it never moves
the estimate. A decoy board seen in ``after`` measurements in a row, with no real landmark
accepted meanwhile, cannot be told from a kidnap by these sensors and is followed, until the
real landmarks are rejected ``after`` times and bring the estimate back. Dead reckoning has no
landmark to re-localise from: it never recovers from a kidnap or an encoder spike.
"""

from __future__ import annotations

import numpy as np

from stsf_gym.geometry import compose, compose_jacobians, inverse, wrap_angle

CANDIDATE_FLOOR_STD = (0.02, 0.02, 0.02)  # m, m, rad: added to every candidate's covariance


class Relocaliser:
    """Collects the candidates of rejected measurements; ``after = 0`` never re-localises
    (``after`` and ``inflation`` are checked by the estimators' settings)."""

    def __init__(self, after: int, inflation: float, gate: float) -> None:
        self.after, self.inflation, self.gate = int(after), float(inflation), gate
        self.candidates: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    def clear(self) -> None:
        """Forget the candidates (a measurement was accepted, or a new episode)."""
        self.candidates = []

    def rejected(
        self, pose: np.ndarray, cov: np.ndarray, mean: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """Note the candidate ``pose`` (covariance ``cov``) of a measurement the gate rejected
        against the estimate ``mean``; the pose to re-initialise at, when enough agree."""
        if self.after == 0:
            return None
        cov = cov + np.diag(np.square(CANDIDATE_FLOOR_STD))
        carried = [self._carried(*c, mean) for c in self.candidates]
        agreeing = [(x, p) for x, p in carried if self._agrees(x, p, pose, cov)]
        self.candidates = [*self.candidates, (pose.copy(), cov.copy(), mean.copy())]
        self.candidates = self.candidates[-(2 * self.after - 1) :]
        if len(agreeing) + 1 < self.after:
            return None
        self.clear()
        return _information_mean([*agreeing, (pose, cov)]), cov * self.inflation

    @staticmethod
    def _carried(old, old_cov, old_mean, mean) -> tuple[np.ndarray, np.ndarray]:
        """An earlier candidate carried to now by the odometry since, with its covariance."""
        odometry = compose(inverse(old_mean), mean)
        jac, _ = compose_jacobians(old, odometry)
        return compose(old, odometry), jac @ old_cov @ jac.T

    def _agrees(self, carried, carried_cov, pose, cov) -> bool:
        error = carried - pose
        error[2] = wrap_angle(error[2])
        return float(error @ np.linalg.solve(carried_cov + cov, error)) <= self.gate


def _information_mean(poses: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Information-weighted mean of poses ``(x, P)``, headings taken relative to the last."""
    reference = poses[-1][0]
    information = sum(np.linalg.inv(p) for _, p in poses)
    weighted = np.zeros(3)
    for x, p in poses:
        offset = x - reference
        offset[2] = wrap_angle(offset[2])
        weighted += np.linalg.solve(p, offset)
    fused = reference + np.linalg.solve(information, weighted)
    fused[2] = wrap_angle(fused[2])
    return fused
