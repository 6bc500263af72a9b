"""The navigation task: follow the world's path to its goal. Progress, reward, termination."""

from __future__ import annotations

import numpy as np

from stsf_gym.envs.config import RewardConfig, WorldConfig


class Polyline:
    """A path of straight segments: arc-length projection and interpolation."""

    def __init__(self, points) -> None:
        self.points = np.asarray(points, dtype=float)
        if self.points.ndim != 2 or len(self.points) < 2:
            raise ValueError(f"a path needs at least 2 points [x, y], got {points!r}")
        self.segments = np.diff(self.points, axis=0)
        self.lengths = np.linalg.norm(self.segments, axis=1)
        if np.any(self.lengths <= 0):
            raise ValueError(f"path has repeated points: {points!r}")
        self.offsets = np.concatenate([[0.0], np.cumsum(self.lengths)])

    @property
    def length(self) -> float:
        return float(self.offsets[-1])

    def project(self, xy: np.ndarray) -> float:
        """Arc length (m) of the path point nearest ``xy``."""
        rel = np.asarray(xy, dtype=float)[:2] - self.points[:-1]
        t = np.clip(np.einsum("ij,ij->i", rel, self.segments) / self.lengths**2, 0.0, 1.0)
        distances = np.linalg.norm(rel - t[:, None] * self.segments, axis=1)
        i = int(np.argmin(distances))
        return float(self.offsets[i] + t[i] * self.lengths[i])

    def point_at(self, s: float) -> np.ndarray:
        """Path point at arc length ``s`` (clamped to the ends)."""
        s = float(np.clip(s, 0.0, self.length))
        i = min(int(np.searchsorted(self.offsets, s, side="right")) - 1, len(self.lengths) - 1)
        return self.points[i] + (s - self.offsets[i]) / self.lengths[i] * self.segments[i]


class PathTask:
    """Progress is the arc length of the path point nearest the robot.

    Reward per step: ``progress * (metres gained) + time * dt``, plus ``goal`` on reaching the
    goal and ``collision`` on touching a wall or obstacle.
    """

    def __init__(self, world: WorldConfig, reward: RewardConfig) -> None:
        self.path = Polyline(world.path)
        self.goal = self.path.points[-1]
        self.goal_radius = world.goal_radius
        self.reward_cfg = reward

    def progress(self, xy: np.ndarray) -> float:
        """Arc length (m) of the path point nearest ``xy``."""
        return self.path.project(xy)

    def reached_goal(self, xy: np.ndarray) -> bool:
        return bool(np.linalg.norm(np.asarray(xy)[:2] - self.goal) <= self.goal_radius)

    def reward(
        self, gained: float, dt: float, reached: bool, collided: bool, steering_change: float = 0.0
    ) -> float:
        cfg = self.reward_cfg
        return (
            cfg.progress * gained
            + cfg.time * dt
            + cfg.goal * reached
            + cfg.collision * collided
            + cfg.steering_change * steering_change
        )
