"""Pure-pursuit path follower driving on a pose (true or estimated), with sonar avoidance."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from stsf_gym.agents.sonar_avoidance import AvoidanceConfig, SonarAvoidance
from stsf_gym.config_files import deep_merge
from stsf_gym.envs.config import CONFIG_DIR, build, overrides_to_tree, read_yaml
from stsf_gym.envs.task import Polyline
from stsf_gym.geometry import bounded


@dataclass(frozen=True)
class ArrivalConfig:
    """How the follower declares arrival (``task.protocol: declare``) on its estimate."""

    tolerance: float  # m: stop when the estimated goal is this close along the path (or passed)
    approach_gain: float  # 1/s: speed = gain * estimated distance left, capped at ``speed`` ...
    min_speed: float  # ... and at least this (m/s), so it gets there


@dataclass(frozen=True)
class FollowerConfig:
    """The path follower's settings (``configs/agents/follower.yaml``)."""

    speed: float
    lookahead: float
    max_yaw_rate: float
    turn_in_place: float
    avoidance: AvoidanceConfig
    arrival: ArrivalConfig


def load_follower_config(path: str | Path | None = None, **overrides) -> FollowerConfig:
    """``configs/agents/follower.yaml`` (or ``path``) with keyword overrides; unknown keys fail.

    Nested keys are overridden as ``avoidance__enabled=False``.
    """
    data = read_yaml(path or CONFIG_DIR / "agents" / "follower.yaml")
    return build(FollowerConfig, deep_merge(data, overrides_to_tree(overrides)), "follower")


class PathFollower:
    """Pure pursuit: steer towards the path point ``lookahead`` metres ahead of the robot.

    The curvature to reach a point (x_r, y_r) in the robot frame is ``2 y_r / d^2``; the
    follower drives at ``speed`` with yaw rate ``speed * curvature`` (clipped), and turns on
    the spot when the point is more than ``turn_in_place`` radians off its heading. Given the
    sonar ranges, :class:`~stsf_gym.agents.sonar_avoidance.SonarAvoidance` (``avoidance`` in the
    config) may bend or slow that command around obstacles. Actions are scaled to the env's ``[-1,
    1]`` box by the robot's ``max_speed`` and ``max_yaw_rate``.

    Under the ``declare`` task (``declares``) the follower heads for the task's current goal as
    the observation gives it (:meth:`see_goal`: its arc length along the path while goals are
    left) and declares arrival where its pose says the goal is: the lookahead point stops at
    the goal, the speed falls as ``approach_gain`` times the distance its estimate has left (at
    least ``min_speed``), and once that is within ``arrival.tolerance`` (or the estimate has
    passed the goal) it commands ``[0, 0]`` for ``hold_steps`` steps (the task's
    ``stop_seconds``), or once with its ``stop`` entry raised (``task.stop_action``), then
    heads for the next goal the observation shows. It turns where its estimate says the turn
    is, as always.

    Before its pose is known (an unknown start the estimator has not localized yet), a path
    follower has nowhere to steer to: :meth:`explore` wanders instead, straight ahead at
    ``speed`` with the sonar avoidance turning it from walls, so the camera gets to see boards.
    """

    def __init__(
        self,
        path,
        cfg: FollowerConfig,
        max_speed: float,
        max_yaw_rate: float,
        avoidance: SonarAvoidance | None = None,
        declares: bool = False,
        hold_steps: int = 0,
        stop_action: bool = False,
    ) -> None:
        self.path, self.cfg, self.avoidance = Polyline(path), cfg, avoidance
        self.scale = np.array([max_speed, max_yaw_rate])
        self.declares, self.hold_steps, self.stop_action = declares, hold_steps, stop_action
        self.goals: list[float] = []  # the goal headed for (arc length), or none
        self._goal, self._holding, self._declared = 0, 0, False
        self.goals_left: int | None = None  # the observation's count when last seen: the goal's id

    @classmethod
    def for_env(cls, env, config: str | Path | None = None, **overrides) -> PathFollower:
        """A follower of ``env``'s world path, scaled to its action space, reading its sonar;
        under ``declare`` it stops at the goals its observations give (:meth:`see_goal`)."""
        env_cfg = env.unwrapped.config
        cfg = load_follower_config(config, **overrides)
        avoidance = None
        if cfg.avoidance.enabled:
            avoidance = SonarAvoidance(
                cfg.avoidance,
                env_cfg.sonar.count,
                env_cfg.robot.body_radius,
                env_cfg.sonar.max_range,
            )
        stop_action = "stop" in env.get_wrapper_attr("action_layout")
        declare = env_cfg.task.protocol == "declare"
        hold = 0
        if declare and not stop_action:
            hold = math.ceil(env_cfg.task.stop_seconds / env_cfg.sim.control_dt - 1e-9) + 1
        return cls(
            env_cfg.world.path,
            cfg,
            env_cfg.robot.max_speed,
            env_cfg.robot.max_yaw_rate,
            avoidance,
            declare,
            hold,
            stop_action,
        )

    def see_goal(self, goal_arc: float, goals_left: int) -> None:
        """The task's current goal as the observation gives it (``obs["goal_arc"]`` and
        ``obs["goals_left"]``): a new goal is headed for; the one it has declared stays declared
        until the task moves on. Nothing without the ``declare`` task."""
        if self.declares and goals_left != self.goals_left:
            self.goals_left = goals_left
            self.goals, self._goal = [goal_arc] if goals_left else [], 0

    def head_for(self, goal_arc: float | None) -> None:
        """Head for the goal ``goal_arc`` metres along the path (None: no goal left), afresh: an
        expert labelling another agent's states follows the task's current goal as the
        observation gives it, wherever that agent's own stops left it."""
        self.goals, self._goal, self._holding = [] if goal_arc is None else [goal_arc], 0, 0

    def explore(self, sonar: np.ndarray | None = None) -> np.ndarray:
        """Action [v, w] that wanders without a pose: ahead, around what the sonar sees."""
        v, w = self.cfg.speed, 0.0
        if sonar is not None and self.avoidance is not None:
            v, w = self.avoidance.adjust(sonar, 0.0, v, w, self.cfg.max_yaw_rate)
        return bounded(np.array([v, w]) / self.scale, -1.0, 1.0).astype(np.float32)

    def act(self, pose: np.ndarray, sonar: np.ndarray | None = None) -> np.ndarray:
        """Action [v, w] in [-1, 1] for the robot at ``pose`` = [x, y, yaw], and a last entry
        ``stop`` (+1 declares, -1 not) when the env has ``task.stop_action``.

        With ``sonar`` (the observation's 16 ranges) and avoidance enabled, obstacles the ring
        sees bend the command; without it this is plain pure pursuit.
        """
        drive = self._drive(pose, sonar)
        if not self.stop_action:
            return drive
        return np.append(drive, np.float32(1.0 if self._declared else -1.0))

    def _drive(self, pose: np.ndarray, sonar: np.ndarray | None) -> np.ndarray:
        """[v, w] for :meth:`act`; sets ``_declared`` when this step declares arrival."""
        along = self.path.project(pose)
        ahead, speed = along + self.cfg.lookahead, self.cfg.speed
        self._declared = False
        if self._holding:  # declaring arrival: stand still
            self._holding -= 1
            return np.zeros(2, np.float32)
        if self._goal < len(self.goals):
            goal = self.goals[self._goal]
            arrival = self.cfg.arrival
            left = max(goal - along, 0.0)
            if left <= arrival.tolerance:
                if not self._may_declare():
                    return self._wait()
                self._goal += 1
                self._holding = max(self.hold_steps - 1, 0)
                self._declared = True
                return np.zeros(2, np.float32)
            ahead = min(ahead, goal)
            speed = min(max(arrival.approach_gain * left, arrival.min_speed), speed)  # np.clip
            speed = self._approach_speed(left, speed)
        return self._pursue(pose, self.path.point_at(ahead), speed, sonar)

    def _pursue(
        self, pose: np.ndarray, target: np.ndarray, speed: float, sonar: np.ndarray | None
    ) -> np.ndarray:
        """[v, w] in [-1, 1] that steers from ``pose`` toward ``target`` (world x, y) at
        ``speed``: pure pursuit, turning on the spot when the target is far off the heading,
        bent by the sonar."""
        x, y, yaw = pose
        dx, dy = target - (x, y)
        c, s = math.cos(yaw), math.sin(yaw)
        x_r, y_r = c * dx + s * dy, -s * dx + c * dy
        bearing = math.atan2(y_r, x_r)
        if abs(bearing) > self.cfg.turn_in_place:
            v, w = 0.0, math.copysign(self.cfg.max_yaw_rate, bearing)
        else:
            curvature = 2 * y_r / max(x_r * x_r + y_r * y_r, 1e-9)
            v = speed
            w = min(max(v * curvature, -self.cfg.max_yaw_rate), self.cfg.max_yaw_rate)
        if sonar is not None and self.avoidance is not None:
            v, w = self.avoidance.adjust(sonar, bearing, v, w, self.cfg.max_yaw_rate)
        return bounded(np.array([v, w]) / self.scale, -1.0, 1.0).astype(np.float32)

    def _may_declare(self) -> bool:
        """Whether to declare now that the estimate is at the goal (always, here; a cautious
        follower may wait, :mod:`stsf_gym.agents.cautious_follower`)."""
        return True

    def _wait(self) -> np.ndarray:
        """[v, w] while waiting at a goal instead of declaring (never called here)."""
        raise NotImplementedError

    def _approach_speed(self, left: float, speed: float) -> float:
        """The speed ``left`` metres (estimated) before the goal: ``speed`` unchanged here."""
        return speed
