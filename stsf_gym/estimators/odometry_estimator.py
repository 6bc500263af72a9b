"""The odometry-only estimator: dead reckoning with propagated covariance."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from stsf_gym.estimators.base import PoseEstimator, SensorModel
from stsf_gym.estimators.odometry_model import odometry_step
from stsf_gym.estimators.pose_errors import PoseErrors
from stsf_gym.estimators.settings import OdometrySettings


class OdometryEstimator(PoseEstimator):
    """Integrates the wheel encoders (mid-point model) with the covariance of slip, a random
    walk, and of the unknown calibration, fixed errors (:mod:`~stsf_gym.estimators.pose_errors`).
    """

    name = "odometry"
    settings_type: ClassVar[type] = OdometrySettings

    def __init__(self, settings: OdometrySettings) -> None:
        """``settings.mount_std`` (m): estimators with a camera consider its mount's position
        error."""
        super().__init__()
        self.settings = settings
        self.mount_std = settings.mount_std

    def believed_odometry(self) -> OdometrySettings | None:
        """Its settings, the odometry noise it propagates (a subclass's own settings type
        that is no :class:`OdometrySettings`: the defaults')."""
        return self.settings if isinstance(self.settings, OdometrySettings) else None

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        super().reset(model, initial_pose, initial_cov)
        # block diagonal: wheel calibration, mount, camera calibration (numpy: the env
        # process then loads no scipy.linalg, about 30 MB)
        calibration = np.asarray(model.odometry_noise.calibration_cov, float)
        considered = np.diag(
            [0.0] * len(calibration)
            + [self.mount_std**2] * 2
            + list(np.square(model.camera_calibration_std))
        )
        n = len(calibration)
        considered[:n, :n] = calibration
        self.errors = PoseErrors(self.cov, considered)

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        with self.timed("odometry"):
            self.predict(obs)
        return self.mean, self.cov

    def predict(self, obs: dict) -> tuple[float, float]:
        """The odometry prediction every estimator starts a step with; returns the wheel
        travels (m)."""
        calibration = self.model.calibration
        d_left, d_right = calibration.wheel_travel(obs["encoders"])
        self.mean, F, G, G_c = odometry_step(self.mean, d_left, d_right, calibration.wheelbase)
        slip = self.model.odometry_noise.slip_cov(d_left, d_right)
        self.errors.predict(F, G @ slip @ G.T, G_c)
        self.cov = self.errors.P
        return d_left, d_right

    def innovations(self) -> list[tuple[float, int]]:
        return list(self.errors.nis)

    def restart(self, mean: np.ndarray, cov: np.ndarray) -> None:
        """Start again from ``mean`` with covariance ``cov`` (re-localisation)."""
        self.mean = np.asarray(mean, dtype=float).copy()
        self.errors.restart(cov)
        self.cov = self.errors.P
