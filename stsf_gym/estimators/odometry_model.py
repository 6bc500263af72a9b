"""The odometry's model: differential-drive dead reckoning from wheel travel, its noise and the
covariance it propagates (the estimator on it: :mod:`~stsf_gym.estimators.odometry_estimator`)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from stsf_gym.validation import NonNegative


@dataclass(frozen=True)
class OdometryNoise:
    """The wheel-travel errors an estimator assumes.

    Slip is a random walk per wheel: ``var(d) = slip_var_per_m * |d|`` for a wheel that rolled
    ``d`` metres. The calibration errors are not: one relative error per wheel radius
    (variance ``radius_var``) and one of the wheelbase (``wheelbase_var``), drawn per episode,
    make the drift grow *linearly* with distance. The estimators carry them as the
    considered parameters ``c`` of :class:`~stsf_gym.estimators.pose_errors.PoseErrors`
    (``calibration_cov``, with the Jacobian of :func:`odometry_step`).
    """

    slip_var_per_m: NonNegative
    radius_var: NonNegative = 0.0
    wheelbase_var: NonNegative = 0.0

    @classmethod
    def from_encoders(
        cls,
        slip_std: float,
        radius_error_std: float,
        wheelbase_error_std: float,
        wheel_radius: float,
    ):
        """Matching the env's encoder model: slip ``slip_std`` rad per sqrt(rad) of rotation,
        and relative wheel-radius and wheelbase errors of std ``radius_error_std`` and
        ``wheelbase_error_std`` that the robot cannot know."""
        return cls(slip_std**2 * wheel_radius, radius_error_std**2, wheelbase_error_std**2)

    @functools.cached_property
    def calibration_cov(self) -> np.ndarray:
        """Covariance of ``c`` = relative errors of left radius, right radius, wheelbase (made
        once, read-only)."""
        cov = np.diag([self.radius_var, self.radius_var, self.wheelbase_var])
        cov.setflags(write=False)
        return cov

    def slip_variances(self, d_left: float, d_right: float) -> np.ndarray:
        """Slip variances (m^2) of the wheel travels ``d_left``, ``d_right`` (m)."""
        return self.slip_var_per_m * np.abs(np.array([d_left, d_right]))

    def slip_cov(self, d_left: float, d_right: float) -> np.ndarray:
        """The two wheel travels' slip covariance, ``np.diag(slip_variances(...))``, written
        out (the same products on floats)."""
        left, right = self.slip_var_per_m * abs(d_left), self.slip_var_per_m * abs(d_right)
        return np.array([[left, 0.0], [0.0, right]])


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
    pose: np.ndarray, d_left: float, d_right: float, wheelbase: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`integrate_wheel_travel` and its Jacobians: ``F`` by the pose, ``G`` by the two
    wheel travels and ``G_c`` by the calibration errors ``c`` (:class:`OdometryNoise`): a wheel
    whose radius is believed ``1 + c_i`` times too large reports ``d c_i`` too much travel, a
    wheelbase believed ``1 + c_3`` times too large turns ``turn c_3`` too little."""
    distance = (d_left + d_right) / 2
    turn = (d_right - d_left) / wheelbase
    mid = pose[2] + turn / 2
    c, s = math.cos(mid), math.sin(mid)
    F = np.array([[1.0, 0.0, -distance * s], [0.0, 1.0, distance * c], [0.0, 0.0, 1.0]])
    k = distance / (2 * wheelbase)
    by_travel = (
        (c / 2 + k * s, c / 2 - k * s),
        (s / 2 - k * c, s / 2 + k * c),
        (-1 / wheelbase, 1 / wheelbase),
    )
    by_turn = (-distance * s / 2, distance * c / 2, 1.0)
    G_c = [
        (left * d_left, right * d_right, -turn * along)
        for (left, right), along in zip(by_travel, by_turn, strict=True)
    ]
    pose_after = integrate_wheel_travel(pose, d_left, d_right, wheelbase)
    return pose_after, F, np.array(by_travel), np.array(G_c)
