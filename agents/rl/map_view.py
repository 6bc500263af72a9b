"""The robot's map as a policy may read it, from the estimated pose: never the truth.

Every estimator and the camera's pointing already use the map (its boards, its walls); a policy
whose input lacks it cannot know where to look. :class:`MapView` gives two parts of it, each an
observation setting of :class:`~stsf_gym.agents.observation.PolicyObservation`:

- :meth:`MapView.boards`: the ``count`` map boards nearest the estimated position, nearest
  first, each as its range over ``scale``, the sine and cosine of its bearing in the estimated
  robot frame, and 1 where the pan camera could see it from the estimated pose (within the
  pointing's range, facing the robot, no wall in the line of sight, within the pan limit:
  :class:`~stsf_gym.estimators.camera_pointing.LandmarkPointer`), else 0. Ranges are cut at
  :data:`BOARD_HORIZON_M`; a missing board (a map of fewer) reads as one at the horizon, dead
  ahead and out of sight.
- :meth:`MapView.sonar`: the ranges the sonar ring would read at the estimated pose in a world
  of the map's walls alone (noise-free, the ring's own rays: :meth:`~stsf_gym.envs.sensors.sonar.
  SonarRing.scene_ranges`), scaled as the measured ones (0 at ``min_range``, 1 at ``max_range``).
  Beside the measured ranges, their difference is what Monte Carlo localization weighs.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

from stsf_gym.envs.rendering.scene import Scene
from stsf_gym.envs.sensors.sonar import SonarRing
from stsf_gym.envs.worlds.corridor import wall_box
from stsf_gym.estimators.camera_pointing import LandmarkPointer
from stsf_gym.wrappers.sensor_model import robot_map

BOARD_HORIZON_M = 10.0  # beyond the pointing's 8 m reach: a board farther is out of sight
BOARD_FEATURES = 4  # range, sin and cos of the bearing, visible


class MapView:
    """The map of ``env``'s current world seen from an estimated pose (see the module)."""

    def __init__(self, env: gym.Env, scale: float) -> None:
        cfg = env.unwrapped.config  # type: ignore[attr-defined]
        landmarks, walls = robot_map(env)
        self.scale = scale
        self._centres = np.array([lm.centre[:2] for lm in landmarks.values()]).reshape(-1, 2)
        self._ids = list(landmarks)
        self._pointer = LandmarkPointer(
            landmarks, walls, cfg.robot.camera_forward, math.radians(cfg.robot.pan_limit_deg)
        )
        self._ring = SonarRing(cfg.sonar, cfg.robot.body_radius)
        self._range = (cfg.sonar.min_range, cfg.sonar.max_range)
        self._scene = Scene()
        for body, wall in enumerate(walls):
            self._scene.add(body, wall_box(wall, cfg.world.wall_thickness, cfg.world.wall_height))

    def boards(self, pose: np.ndarray, count: int) -> np.ndarray:
        """``(count * 4,)``: the nearest boards' range / scale, sin and cos of their bearing,
        and whether the camera could see them, from ``pose`` = ``[x, y, yaw]``."""
        x, y, yaw = (float(v) for v in pose)
        offsets = self._centres - (x, y)
        ranges = np.hypot(offsets[:, 0], offsets[:, 1])
        visible = {self._ids[index] for index, _ in self._pointer.candidates(np.array([x, y, yaw]))}
        features = np.tile([BOARD_HORIZON_M / self.scale, 0.0, 1.0, 0.0], (count, 1))
        for row, index in enumerate(np.argsort(ranges, kind="stable")[:count]):
            bearing = math.atan2(offsets[index, 1], offsets[index, 0]) - yaw
            features[row] = (
                min(ranges[index], BOARD_HORIZON_M) / self.scale,
                math.sin(bearing),
                math.cos(bearing),
                float(self._ids[index] in visible),
            )
        return features.ravel()

    def sonar(self, pose: np.ndarray) -> np.ndarray:
        """The sonar ranges the map predicts at ``pose``, 0 at ``min_range`` to 1 at
        ``max_range``."""
        low, high = self._range
        ranges = np.clip(self._ring.scene_ranges(self._scene, np.asarray(pose, float)), low, high)
        return (ranges - low) / (high - low)
