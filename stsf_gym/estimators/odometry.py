"""Differential-drive dead reckoning from wheel travel, with propagated covariance."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OdometryNoise:
    """Wheel-travel noise an estimator assumes, per wheel and per step.

    ``var(d) = slip_var_per_m * |d| + (scale_std * d)^2`` for a wheel that rolled ``d``
    metres: a random walk from slip, plus a share of the unknown calibration error.
    """

    slip_var_per_m: float
    scale_std: float

    @classmethod
    def from_encoders(
        cls,
        slip_std: float,
        radius_error_std: float,
        wheel_radius: float,
        calibration_length: float = 5.0,
    ):
        """Matching the env's encoder model: slip ``slip_std`` rad per sqrt(rad) of rotation,
        and a wheel-radius error of relative std ``radius_error_std`` that the robot cannot
        know. That error is systematic; it is modelled as a random walk with the same variance
        after ``calibration_length`` metres, which keeps the covariance from being
        over-confident over tens of metres without making it useless over a few."""
        return cls(slip_std**2 * wheel_radius + radius_error_std**2 * calibration_length, 0.0)

    def wheel_variances(self, d_left: float, d_right: float) -> np.ndarray:
        d = np.array([d_left, d_right])
        return self.slip_var_per_m * np.abs(d) + (self.scale_std * d) ** 2


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


def propagate(
    pose: np.ndarray,
    cov: np.ndarray,
    d_left: float,
    d_right: float,
    wheelbase: float,
    noise: OdometryNoise,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`integrate_wheel_travel` with first-order covariance ``F C F^T + G N G^T``.

    ``F`` is the Jacobian with respect to the pose and ``G`` with respect to the two
    wheel travels, whose noise ``N`` is :meth:`OdometryNoise.wheel_variances`.
    """
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
    N = np.diag(noise.wheel_variances(d_left, d_right))
    new_cov = F @ cov @ F.T + G @ N @ G.T
    return integrate_wheel_travel(pose, d_left, d_right, wheelbase), (new_cov + new_cov.T) / 2
