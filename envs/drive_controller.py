"""The wheel velocity controller: commanded (v, w) through velocity and acceleration limits.

The model of ROS ``diff_drive_controller``'s speed limiter: at each control update of period
``dt`` the commanded forward speed ``v`` and yaw rate ``w`` are clamped to their velocity
limits, and their change to ``max_acceleration * dt`` (linear) and ``max_yaw_acceleration * dt``
(angular), each limited on its own. The limited (v, w) becomes the two wheels' target angular
velocities ``(v -+ w b / 2) / r``, which PyBullet's wheel motors track within their torque.
Commands thus reach the wheels as a real base's would: ramps, not steps, so the wheels need
far less than their friction to follow and a reversing turn does not skid.
"""

from __future__ import annotations

import numpy as np

from stsf_gym.envs.config import RobotConfig
from stsf_gym.geometry import clamp


class VelocityController:
    """Speed limiter of (v, w) in m/s and rad/s (``robot`` section of the config)."""

    def __init__(self, cfg: RobotConfig) -> None:
        self.max_velocity = (cfg.max_speed, cfg.max_yaw_rate)
        self.max_acceleration = (cfg.max_acceleration, cfg.max_yaw_acceleration)
        self._command = (0.0, 0.0)

    def reset(self) -> None:
        """At rest."""
        self._command = (0.0, 0.0)

    def update(self, target: np.ndarray, dt: float) -> tuple[float, float]:
        """The (v, w) sent to the wheels ``dt`` seconds after the previous update, moving
        towards ``target`` as fast as the acceleration limits allow. Plain floats: two numbers
        an update, six updates a step, cost more in numpy's call overhead than in arithmetic."""
        (v, w), (v_max, w_max), (a_v, a_w) = (
            self._command,
            self.max_velocity,
            self.max_acceleration,
        )
        self._command = (
            v + clamp(clamp(float(target[0]), v_max) - v, a_v * dt),
            w + clamp(clamp(float(target[1]), w_max) - w, a_w * dt),
        )
        return self._command
