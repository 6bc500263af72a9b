"""The odometry-only estimator: dead reckoning with propagated covariance."""

from __future__ import annotations

import numpy as np

from stsf_gym.estimators.base import PoseEstimator
from stsf_gym.estimators.odometry import propagate


class OdometryEstimator(PoseEstimator):
    """Integrates the wheel encoders (mid-point model); the covariance only grows."""

    name = "odometry"

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        with self.timed("odometry"):
            self.predict(obs)
        return self.mean, self.cov

    def predict(self, obs: dict) -> None:
        """The odometry prediction every estimator starts a step with."""
        calibration = self.model.calibration
        d_left, d_right = calibration.wheel_travel(obs["encoders"])
        self.mean, self.cov = propagate(
            self.mean, self.cov, d_left, d_right, calibration.wheelbase, self.model.odometry_noise
        )
