"""The navigation task: follow the world's path to its goal(s). Progress, reward, termination,
and the two success protocols (``task.protocol``: ``reach``, the paper's, or ``declare``)."""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from stsf_gym.envs.config import RewardConfig, TaskConfig, WorldConfig
from stsf_gym.validation import WORLD_EXTENT_M

MAX_GOALS = 2**31 - 1  # the bound of the goal counts' Box: a route lists any number of goals
MAX_ARC_M = 1e9  # the goal's arc length's bound: beyond any path (finite, as checkers ask)


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
        self._offsets = self.offsets.tolist()  # for bisect: np.searchsorted's answers, cheaper
        self._segments = [  # start, vector, length, its square, arc length at the start
            (tuple(start), tuple(vector), length, length * length, offset)
            for start, vector, length, offset in zip(
                self.points[:-1].tolist(),
                self.segments.tolist(),
                self.lengths.tolist(),
                self.offsets[:-1].tolist(),
                strict=True,
            )
        ]

    @property
    def length(self) -> float:
        return float(self.offsets[-1])

    def project(self, xy: np.ndarray) -> float:
        """Arc length (m) of the path point nearest ``xy``. Plain floats: a path has a few
        segments, fewer than numpy's call overhead pays for (the same arithmetic, the same
        result to the last bit)."""
        x, y = float(xy[0]), float(xy[1])
        best, arc = math.inf, 0.0
        for (px, py), (sx, sy), length, squared, offset in self._segments:
            rx, ry = x - px, y - py
            t = min(max((rx * sx + ry * sy) / squared, 0.0), 1.0)
            dx, dy = rx - t * sx, ry - t * sy
            distance = math.sqrt(dx * dx + dy * dy)
            if not distance >= best:  # the first nearest, as argmin; NaN in, NaN out
                best, arc = distance, offset + t * length
        return arc

    def point_at(self, s: float) -> np.ndarray:
        """Path point at arc length ``s`` (clamped to the ends)."""
        s, i = self._segment(s)
        return self.points[i] + (s - self.offsets[i]) / self.lengths[i] * self.segments[i]

    def heading_at(self, s: float) -> float:
        """Direction (rad) of the path's segment at arc length ``s``."""
        dx, dy = self.segments[self._segment(s)[1]]
        return float(np.arctan2(dy, dx))

    def _segment(self, s: float) -> tuple[float, int]:
        s = float(min(max(s, 0.0), self._offsets[-1]))  # np.clip's result, NaN kept
        i = min(bisect.bisect_right(self._offsets, s) - 1, len(self.lengths) - 1)
        return s, i


@dataclass(frozen=True)
class Stop:
    """A declared arrival: which goal, when, where (true), how far from the goal, success."""

    goal: int
    time: float
    position: tuple[float, float]
    true_distance_m: float
    success: bool


class PathTask:
    """Progress, reward and the episode's end under ``task.protocol``.

    Progress is the arc length of the path point nearest the robot (under ``declare`` no further
    than the current goal's, so driving past a goal earns nothing). Reward per step:
    ``progress * (metres gained) + time * dt``, plus ``goal`` on each goal reached and
    ``collision`` on touching a wall or obstacle.

    - ``reach`` (the paper's reach-the-goal protocol, Table I and Fig. 10/11): the goal is
      reached, and the episode ends as a success, when the TRUE position enters the world's
      ``goal_radius`` around the path's end; the agent decides nothing.
    - ``declare`` (Habitat PointNav's STOP, Anderson et al. 2018): the goals are the world's
      ``route`` (or the path's end) in order. The agent **declares arrival by standing still**:
      a commanded ``|v| < stop_speed`` and ``|w| < stop_yaw_rate`` held for ``stop_seconds``,
      after it has moved since the last declaration (or the reset). At a declaration the true
      position is compared with the current goal: within ``task.goal_radius`` the goal is
      reached and the next one becomes current (the last one ends the episode as a success);
      outside it the episode ends as a failure. The truth crossing a goal never ends anything.
      Standing still keeps every agent's action space (``Box`` ``[v, w]``, plus the camera
      mount) as it is, and is how a real robot ends a delivery. With ``task.stop_action`` the
      action has a last entry ``stop`` (:mod:`stsf_gym.envs.action_layout`): above 0 it
      declares arrival at once, judged alike (Habitat's STOP); standing still is then just
      standing still. A declared stop off its goal costs ``reward.false_stop``.

    :meth:`set_goals` replaces the route's goals for one episode (a training leg,
    :func:`~stsf_gym.envs.start_pose.draw_leg`).
    """

    def __init__(self, world: WorldConfig, reward: RewardConfig, task: TaskConfig) -> None:
        self.path = Polyline(world.path)
        self.protocol = task.protocol
        self.cfg = task
        self.goal_radius = task.goal_radius if task.protocol == "declare" else world.goal_radius
        self.reward_cfg = reward
        self.set_goals(world.goals if task.protocol == "declare" else world.path[-1:])

    def set_goals(self, goals) -> None:
        """Visit ``goals`` (points on the path, in order) from now on; starts afresh."""
        self.goals = np.asarray(goals, dtype=float).reshape(-1, 2)
        self.goal_arcs = [self.path.project(goal) for goal in self.goals]
        self.reset()

    def reset(self) -> None:
        """Start an episode: the first goal, no stops declared."""
        self.goal_index = 0
        self.stops: list[Stop] = []
        self._still, self._armed = 0.0, False
        self._false_now = False  # this step's declaration was off its goal

    @property
    def goal(self) -> np.ndarray:
        """The current goal (the last one once every goal is reached)."""
        return self.goals[min(self.goal_index, len(self.goals) - 1)]

    @property
    def success(self) -> bool:
        """Every goal reached (declared in order, or the path's end entered under ``reach``)."""
        return self.goal_index >= len(self.goals)

    def progress(self, xy: np.ndarray) -> float:
        """Arc length (m) of the path point nearest ``xy`` (``declare``: at most the current
        goal's)."""
        s = self.path.project(xy)
        if self.protocol == "declare":
            return min(s, self.goal_arcs[min(self.goal_index, len(self.goals) - 1)])
        return s

    @property
    def goals_left(self) -> int:
        """Goals of the route still to declare (0 once every goal is reached)."""
        return len(self.goals) - self.goal_index

    @staticmethod
    def observation_space() -> dict[str, spaces.Space]:
        """The spaces of :meth:`observation`: a goal's position is a world coordinate, its arc
        length any length of path (float64, as the task holds them, so a policy reading them
        computes the same numbers it did from the task itself)."""
        count = spaces.Box(0, MAX_GOALS, (1,), np.int64)
        return {
            "goal": spaces.Box(-WORLD_EXTENT_M, WORLD_EXTENT_M, (2,), np.float64),
            "goal_arc": spaces.Box(0.0, MAX_ARC_M, (1,), np.float64),
            "goals_left": count,
            "goal_count": count,
        }

    def observation(self) -> dict[str, np.ndarray]:
        """The task's public map knowledge: the current goal (world frame, m; the last one once
        every goal is reached), its arc length along the path (m), the goals still to declare
        and the goals of this episode's route."""
        index = min(self.goal_index, len(self.goals) - 1)
        return {
            "goal": self.goals[index].copy(),
            "goal_arc": np.array([self.goal_arcs[index]]),
            "goals_left": np.array([self.goals_left], np.int64),
            "goal_count": np.array([len(self.goals)], np.int64),
        }

    def distance_to_goal(self, xy: np.ndarray) -> float:
        """Distance (m) from ``xy`` to the current goal."""
        return float(np.linalg.norm(np.asarray(xy)[:2] - self.goal))

    def update(
        self, xy: np.ndarray, v: float, w: float, dt: float, time: float, stop: bool = False
    ) -> bool:
        """Advance by one control step with the TRUE position ``xy``, the commanded speed ``v``
        (m/s) and yaw rate ``w`` (rad/s) and the action's ``stop`` entry (``task.stop_action``);
        True when a goal was reached at this step."""
        self._false_now = False
        if self.protocol == "reach":
            reached = self.distance_to_goal(xy) <= self.goal_radius
            self.goal_index += int(reached)
            return reached
        if self.cfg.stop_action:
            return self._declare(xy, time) if stop else False
        if abs(v) >= self.cfg.stop_speed or abs(w) >= self.cfg.stop_yaw_rate:
            self._still, self._armed = 0.0, True
            return False
        if not self._armed:
            return False
        self._still += dt
        if self._still < self.cfg.stop_seconds - 1e-9:
            return False
        return self._declare(xy, time)

    def _declare(self, xy: np.ndarray, time: float) -> bool:
        """A declared arrival at the TRUE position ``xy``: a success within the goal radius."""
        distance = self.distance_to_goal(xy)
        success = distance <= self.goal_radius
        position = (float(xy[0]), float(xy[1]))
        self.stops.append(Stop(self.goal_index, time, position, distance, success))
        self._still, self._armed, self._false_now = 0.0, False, not success
        self.goal_index += int(success)
        return success

    @property
    def missed(self) -> bool:
        """A declared stop was off its goal (``declare``) and ends the episode as a failure
        (always, unless the training-only ``task.false_stop_ends`` is false)."""
        return self.cfg.false_stop_ends and any(not stop.success for stop in self.stops)

    @property
    def finished(self) -> bool:
        """The episode ends: every goal reached, or (``declare``) a declared stop missed."""
        return self.success or self.missed

    def reward(
        self, gained: float, dt: float, reached: bool, collided: bool, steering_change: float = 0.0
    ) -> float:
        """The step's reward, its terms (``reward:``; signs checked by
        :class:`~stsf_gym.envs.config.EnvConfig` under ``declare``):

        - ``progress`` per metre ``gained`` of :meth:`progress`, a potential (Ng et al. 1999):
          the return's sum of it is the progress at the end minus at the start, so no metre of a
          leg is paid twice (driving back and forth nets 0, past the goal earns 0); correct stops
          in the radius differ by their offset along the path (at most the radius, 0.25 m: a
          fortieth of the goal bonus);
        - ``time`` (< 0 under ``declare``) per second ``dt``: dawdling to the time limit costs;
        - ``goal`` (> 0) once per goal ``reached``, judged at the TRUE position of the declared
          stop (what the task judges; the observation never sees it);
        - ``false_stop`` at a declared stop off its goal: once, as it ends the episode, at most
          ``time * sim.max_episode_seconds``, so it never pays better than trying on (standing
          until the time limit costs at most that, and keeps the progress made); under the
          training-only ``task.false_stop_ends: false`` at each such stop, below 0, so a
          declaration off the goal never pays better than none;
        - ``collision`` once, at the collision that ends the episode;
        - ``steering_change`` (<= 0) per unit change of the yaw command.
        """
        cfg = self.reward_cfg
        return (
            cfg.progress * gained
            + cfg.time * dt
            + cfg.goal * reached
            + cfg.collision * collided
            + cfg.false_stop * self._false_now
            + cfg.steering_change * steering_change
        )
