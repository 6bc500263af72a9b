"""The odometry-only estimator: dead reckoning with propagated covariance."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from stsf_gym.estimators.base import PoseEstimator, SensorModel
from stsf_gym.estimators.odometry import odometry_step


class OdometryEstimator(PoseEstimator):
    """Integrates the wheel encoders (mid-point model); the covariance only grows."""

    name = "odometry"

    def __init__(self, calibration_length: float = 5.0) -> None:
        """``calibration_length``: metres at which the odometry noise's random walk matches the
        drift of the wheel-radius calibration error (:class:`OdometryNoise`)."""
        super().__init__()
        if not calibration_length > 0:
            raise ValueError(f"calibration_length must be positive, got {calibration_length}")
        self.calibration_length = float(calibration_length)

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        noise = replace(model.odometry_noise, calibration_length=self.calibration_length)
        super().reset(replace(model, odometry_noise=noise), initial_pose, initial_cov)

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        with self.timed("odometry"):
            self.predict(obs)
        return self.mean, self.cov

    def predict(self, obs: dict) -> tuple[np.ndarray, np.ndarray]:
        """The odometry prediction every estimator starts a step with; returns its Jacobian
        ``F`` and noise ``Q`` (:func:`~stsf_gym.estimators.odometry.odometry_step`)."""
        calibration = self.model.calibration
        d_left, d_right = calibration.wheel_travel(obs["encoders"])
        self.mean, F, Q = odometry_step(
            self.mean, d_left, d_right, calibration.wheelbase, self.model.odometry_noise
        )
        cov = F @ self.cov @ F.T + Q
        self.cov = (cov + cov.T) / 2
        return F, Q
