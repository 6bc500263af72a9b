"""Differential-drive dead reckoning from wheel travel."""

from __future__ import annotations

import math

import numpy as np


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
