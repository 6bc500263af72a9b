"""Wheel encoders: ticks per revolution, quantisation, calibration errors and wheel slip.

The robot's true wheel rotation comes from the simulator. The encoders report the tick count
change of each wheel per step; wheel slip perturbs the counted rotation (a random walk whose
variance grows with the rotation). Calibration errors model a robot whose believed wheel radii
and wheelbase are off from the true ones: :attr:`WheelEncoders.calibration` is what an
odometry estimator must use, drawn anew at each reset from the episode's calibration stream;
slip comes from its encoder stream (:mod:`stsf_gym.envs.random_streams`).
"""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.envs.config import ConfigError, EncoderConfig
from stsf_gym.geometry import OdometryCalibration


class WheelEncoders:
    """Quadrature encoders on both driven wheels, reporting tick deltas per step."""

    def __init__(self, cfg: EncoderConfig, wheel_radius: float, wheelbase: float) -> None:
        if cfg.ticks_per_rev < 1:
            raise ConfigError(f"encoders.ticks_per_rev must be >= 1, got {cfg.ticks_per_rev}")
        self.cfg, self.wheel_radius, self.wheelbase = cfg, wheel_radius, wheelbase
        self.calibration = OdometryCalibration(
            cfg.ticks_per_rev, wheel_radius, wheel_radius, wheelbase
        )
        self._counts = np.zeros(2)  # continuous counted revolutions x ticks, before quantisation
        self._last_angles = np.zeros(2)

    def reset(self, wheel_angles: np.ndarray, rng: np.random.Generator) -> None:
        """Start at ``wheel_angles``: draw the calibration errors the robot does not know."""
        cfg = self.cfg
        radius_errors = rng.normal(size=2) * cfg.radius_error_std
        wheelbase_error = rng.normal() * cfg.wheelbase_error_std
        self.calibration = OdometryCalibration(
            cfg.ticks_per_rev,
            self.wheel_radius * (1 + radius_errors[0]),
            self.wheel_radius * (1 + radius_errors[1]),
            self.wheelbase * (1 + wheelbase_error),
        )
        self._counts = np.zeros(2)
        self._last_angles = np.array(wheel_angles, dtype=float)

    def read(self, wheel_angles: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Tick deltas (int64 [left, right]) since the previous read."""
        rotation = np.asarray(wheel_angles, dtype=float) - self._last_angles
        self._last_angles = np.array(wheel_angles, dtype=float)
        slip = rng.normal(size=2) * self.cfg.slip_std * np.sqrt(np.abs(rotation))
        before = np.floor(self._counts)
        self._counts += (rotation + slip) * self.cfg.ticks_per_rev / (2 * math.pi)
        return (np.floor(self._counts) - before).astype(np.int64)
