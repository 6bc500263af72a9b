"""The paper's conventional fusion: the robot pose measured from the current two frames only.

"In the conventional fusion schemes, the measurement is dependent on the current data sets
only" (sect. 1); Table I's conventional column uses "two consecutive image frames". So on a
camera frame with landmark measurements, each a motion-stereo pair of the current frame and
the landmark's key frame (:mod:`stsf_gym.estimators.landmark_fusion`), the estimate *becomes*
the robot pose they give: the frame's landmarks fused by eq. 1 with inverse-variance weights,
each mapped through its map pose. Between such frames the pose moves by odometry. No landmark
information outlives the pair: no track, and the earlier estimate is not merged in
(``conventional-filter`` does that).

The odometry prediction still serves one purpose, a sanity test: a measured pose outside the
Mahalanobis gate of the prediction is rejected as a wrong detection (and rejections that agree
re-localise, as for the other estimators). Its covariance is the measurement's, correlated with
the considered calibration errors (:meth:`~stsf_gym.estimators.pose_errors.PoseErrors.replace`),
so the NEES stays meaningful.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from stsf_gym.estimators.landmark_fusion import LandmarkFusionEstimator
from stsf_gym.estimators.landmark_observation import LandmarkObservation, robot_pose_from_landmark
from stsf_gym.estimators.settings import ConventionalSettings
from stsf_gym.fusion.spatial import inverse_variance_weights
from stsf_gym.geometry import wrap_angle


class ConventionalEstimator(LandmarkFusionEstimator):
    """The paper's conventional fusion (see the module docstring)."""

    name = "conventional"
    settings_type: ClassVar[type] = ConventionalSettings

    def __init__(self, settings: ConventionalSettings) -> None:
        super().__init__(settings, max_track_frames=1, weights="significance")
        self.measured: list[tuple[LandmarkObservation, np.ndarray, np.ndarray, np.ndarray]] = []

    def _frame(self, obs: dict) -> None:
        self.measured = []
        super()._frame(obs)  # collects the frame's pair measurements (_fuse)
        if self.measured:
            self._measure()

    def _fuse(self, current: LandmarkObservation, z, cov, by_calibration) -> None:
        self.measured.append((current, z, cov, by_calibration))

    def _measure(self) -> None:
        """The frame's measured robot pose (eq. 1 over its landmarks) becomes the estimate."""
        poses, covs, by_considered = [], [], []
        for current, z, cov, by_calibration in self.measured:
            pose, _ = robot_pose_from_landmark(current.landmark, z, cov)
            pose_cov, by_c = self._robot_pose_errors(current, z, cov, by_calibration)
            poses.append(pose)
            covs.append(pose_cov)
            by_considered.append(by_c)
        offsets = np.array(poses) - poses[0]
        offsets[:, 2] = wrap_angle(offsets[:, 2])
        weights = inverse_variance_weights(np.array(covs))  # (n, 3, 3), eq. 1
        pose = poses[0] + np.einsum("nab,nb->a", weights, offsets)
        cov = np.einsum("nab,nbc,ndc->ad", weights, np.array(covs), weights)
        by_c = np.einsum("nab,nbc->ac", weights, np.array(by_considered))
        innovation = pose - self.mean
        innovation[2] = wrap_angle(innovation[2])
        if self.errors.replace(cov, by_c, innovation, self.gate):
            self._accepted(pose)
        else:
            for current, *_ in self.measured:
                self._rejected(current)
        self.measured = []
