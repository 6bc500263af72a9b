"""Differential-drive dead reckoning from wheel travel, with propagated covariance."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OdometryNoise:
    """Wheel-travel noise an estimator assumes, per wheel and per step: a random walk,
    ``var(d) = (slip_var_per_m + radius_var * calibration_length) * |d|`` for a wheel that
    rolled ``d`` metres.

    Slip is a random walk. The wheel-radius calibration error (relative variance
    ``radius_var``) is not: it is one unknown scale per wheel and episode, so its drift grows
    linearly with distance, which a per-step model cannot follow. It is modelled as the random
    walk with the same variance after ``calibration_length`` metres: a filter's covariance is
    right at that distance, too wide before it and too narrow after. Dead reckoning should
    match it at the length of a run; a filter corrected by landmarks at the length it drives
    between corrections.
    """

    slip_var_per_m: float
    radius_var: float = 0.0
    calibration_length: float = 5.0

    @classmethod
    def from_encoders(cls, slip_std: float, radius_error_std: float, wheel_radius: float):
        """Matching the env's encoder model: slip ``slip_std`` rad per sqrt(rad) of rotation,
        and a wheel-radius error of relative std ``radius_error_std`` that the robot cannot
        know."""
        return cls(slip_std**2 * wheel_radius, radius_error_std**2)

    def wheel_variances(self, d_left: float, d_right: float) -> np.ndarray:
        var_per_m = self.slip_var_per_m + self.radius_var * self.calibration_length
        return var_per_m * np.abs(np.array([d_left, d_right]))


def integrate_wheel_travel(
    pose: np.ndarray, d_left: float, d_right: float, wheelbase: float
) -> np.ndarray:
    """Pose [x, y, yaw] after the wheels rolled ``d_left`` and ``d_right`` metres.

    Mid-point (second-order) integration: the robot moves ``(d_left + d_right) / 2`` along
    the heading halfway through its turn of ``(d_right - d_left) / wheelbase``.
    """
    x, y, yaw = pose
    distance = (d_left + d_right) / 2
    turn = (d_right - d_left) / wheelbase
    mid = yaw + turn / 2
    return np.array([x + distance * math.cos(mid), y + distance * math.sin(mid), yaw + turn])


def odometry_step(
    pose: np.ndarray,
    d_left: float,
    d_right: float,
    wheelbase: float,
    noise: OdometryNoise,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`integrate_wheel_travel`, its Jacobian ``F`` by the pose and its noise in pose
    coordinates ``Q = G N G^T`` (``G``: Jacobian by the two wheel travels, ``N``:
    :meth:`OdometryNoise.wheel_variances`)."""
    distance = (d_left + d_right) / 2
    mid = pose[2] + (d_right - d_left) / (2 * wheelbase)
    c, s = math.cos(mid), math.sin(mid)
    F = np.array([[1.0, 0.0, -distance * s], [0.0, 1.0, distance * c], [0.0, 0.0, 1.0]])
    k = distance / (2 * wheelbase)
    G = np.array(
        [
            [c / 2 + k * s, c / 2 - k * s],
            [s / 2 - k * c, s / 2 + k * c],
            [-1 / wheelbase, 1 / wheelbase],
        ]
    )
    Q = G @ np.diag(noise.wheel_variances(d_left, d_right)) @ G.T
    return integrate_wheel_travel(pose, d_left, d_right, wheelbase), F, Q


def propagate(
    pose: np.ndarray,
    cov: np.ndarray,
    d_left: float,
    d_right: float,
    wheelbase: float,
    noise: OdometryNoise,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`integrate_wheel_travel` with first-order covariance ``F C F^T + Q``
    (:func:`odometry_step`)."""
    new_pose, F, Q = odometry_step(pose, d_left, d_right, wheelbase, noise)
    new_cov = F @ cov @ F.T + Q
    return new_pose, (new_cov + new_cov.T) / 2
