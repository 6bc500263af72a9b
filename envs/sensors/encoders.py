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

from stsf_gym.envs.config import EncoderConfig
from stsf_gym.geometry import OdometryCalibration, compiled
from stsf_gym.validation import ConfigError


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
        angles = np.array(wheel_angles, dtype=float)
        cfg = self.cfg
        ticks = _ticks(
            angles,
            self._last_angles,
            self._counts,
            rng.normal(size=2),
            cfg.slip_std,
            cfg.ticks_per_rev,
        )
        self._last_angles = angles
        return ticks


@compiled
def _ticks(
    angles: np.ndarray,
    last_angles: np.ndarray,
    counts: np.ndarray,
    normal: np.ndarray,
    slip_std: float,
    ticks_per_rev: int,
) -> np.ndarray:
    """Each wheel's rotation since ``last_angles``, plus slip (``normal`` times ``slip_std``
    times the square root of the rotation's size), counted onto ``counts`` (in place) in
    ticks; the whole ticks crossed, as int64: the numpy expressions of one wheel each, in the
    same order."""
    ticks = np.empty(len(angles), np.int64)
    for i in range(len(angles)):
        rotation = angles[i] - last_angles[i]
        slip = normal[i] * slip_std * np.sqrt(np.abs(rotation))
        before = np.floor(counts[i])
        counts[i] += (rotation + slip) * ticks_per_rev / (2 * math.pi)
        ticks[i] = np.int64(np.floor(counts[i]) - before)
    return ticks
