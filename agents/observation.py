"""The RL policy's input: pose-derived path features, pose uncertainty, sonar, wheel speeds.

:class:`PolicyObservation` sits on top of a :class:`stsf_gym.wrappers.PoseEstimateWrapper`
and turns its ``Dict`` observation into one flat ``Box``. Everything comes from the pose
estimate, the sensors, the task's goals in the observation and the episode's path, read from
the reset's ``info["path"]`` (public map knowledge), never from the rest of ``info`` or the
env's task.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Annotated, Any, Literal

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from stsf_gym.agents.rl.map_view import BOARD_FEATURES, MapView
from stsf_gym.agents.rl.residual import PROPOSAL
from stsf_gym.envs.config import build
from stsf_gym.envs.task import Polyline
from stsf_gym.validation import Positive, Range

STD_FLOOR, STD_CEIL = 1e-3, 10.0  # clip range of a standard deviation before its log
TANGENT_STEP = 0.1  # m, arc length over which the path's direction is measured
TASK_KEYS = ("goal", "goal_arc", "goals_left", "goal_count")  # read from the observation
FEATURE_LIMIT = 100.0  # every entry is clipped to +-this (only far-off lookahead points reach it)


@dataclass(frozen=True)
class ObservationConfig:
    """``lookahead``: arc lengths (m) ahead of the robot's nearest path point whose positions
    in the robot frame the policy sees; ``scale``: metres that map to 1 in those features;
    ``goal_horizon``: metres beyond which the goal features saturate (None: never). An agent
    trained on legs a few metres long meets goals 20-40 m away on a full route, inputs it has
    never seen; saturated at a horizon its legs reach, they read as a goal at the horizon.
    ``far_goal`` says which: ``direction``, the goal's own direction (the straight line to a
    goal can point back across a wall when the route turns around); ``route``, the route's
    point ``goal_horizon`` metres ahead along the path, as a leg's goal that far ahead reads.
    The robot's map (:mod:`~stsf_gym.agents.rl.map_view`, from the estimate): ``boards``, the
    nearest map boards in the input (0: none); ``predicted_sonar``, the ranges the map predicts
    at the estimated pose beside the measured ones. Both off by default, so agents trained
    before them keep their inputs."""

    lookahead: tuple[float, ...] = (0.0, 0.5, 1.0, 2.0, 4.0)
    scale: Positive = 4.0
    goal_horizon: Positive | None = None
    far_goal: Literal["direction", "route"] = "direction"
    boards: Annotated[int, Range(ge=0)] = 0
    predicted_sonar: bool = False


def observation_config(data: Mapping[str, Any] | None) -> ObservationConfig:
    """An :class:`ObservationConfig` from a mapping; unknown keys raise ``ConfigError``."""
    return build(ObservationConfig, data or {}, "observation")


class PolicyObservation(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """A flat ``Box`` observation in the robot frame, for MLP policies. Entries, in order:

    - ``2 K`` lookahead points: ``(x, y)`` of the path points ``lookahead`` metres ahead of the
      path point nearest the estimated pose, in the estimated robot frame, over ``scale``;
    - the path length left to the current goal (negative past it), over ``scale``;
    - the current goal of the route (``obs["goal"]``, ``declare``: where to stop next) in the
      estimated robot frame, over ``scale`` (Habitat's GPS+compass goal vector, from the
      estimate), and the share of the route's goals still to declare (``obs["goals_left"]``
      over ``obs["goal_count"]``); the path left (to ``obs["goal_arc"]``) is cut at
      ``goal_horizon`` and the goal vector beyond it as ``far_goal`` says;
    - ``sin`` and ``cos`` of the heading error (path direction minus estimated yaw);
    - ``log10`` of the standard deviations of the estimate along and across the robot's
      heading and of its yaw (each clipped to 1 mm..10 m or rad), over 3;
    - the sonar ranges, 0 at ``min_range`` to 1 at ``max_range``;
    - the wheel speeds from the encoder ticks, 1 at the robot's top speed;
    - with ``boards`` = K: 4 K entries, each of the K map boards nearest the estimated position
      as range over ``scale``, sine and cosine of its bearing, and 1 if the camera could see it
      (:meth:`~stsf_gym.agents.rl.map_view.MapView.boards`);
    - with ``predicted_sonar``: the sonar ranges the map predicts at the estimated pose, scaled
      as the measured ones (:meth:`~stsf_gym.agents.rl.map_view.MapView.sonar`);
    - over a :class:`~stsf_gym.agents.rl.residual.ResidualFollower` (its ``follower_action``
      in the observation): the follower's action ``[v, w, stop]`` for this state.

    ``info["is_success"]`` tells at the end of an episode whether every goal was reached
    (under the task's protocol), which stable-baselines3's evaluation callback and ``Monitor``
    count; it is False before, from the reset on, so a recorder sees one type through the
    episode (:mod:`~stsf_gym.envs.step_info`).
    """

    def __init__(
        self, env: gym.Env, config: ObservationConfig | Mapping[str, Any] | None = None
    ) -> None:
        if not isinstance(config, ObservationConfig):  # a mapping, as a JSON spec holds it
            config = observation_config(config)
        # recorded as plain values, so the env's spec survives EnvSpec.to_json/from_json
        recorded = {**asdict(config), "lookahead": list(config.lookahead)}  # as JSON reads it
        gym.utils.RecordConstructorArgs.__init__(self, config=recorded)
        gym.ObservationWrapper.__init__(self, env)
        missing = sorted({"pose", *TASK_KEYS} - set(env.observation_space.spaces))
        if "pose" in missing:
            raise ValueError("PolicyObservation needs obs['pose']: wrap in PoseEstimateWrapper")
        if missing:
            raise ValueError(f"PolicyObservation needs the task's obs keys {missing}")
        self.config = config
        cfg = env.unwrapped.config
        self.path = Polyline(cfg.world.path)  # until a reset gives the episode's
        self.sonar_range = (cfg.sonar.min_range, cfg.sonar.max_range)
        top_wheel_speed = cfg.robot.max_speed / cfg.robot.wheel_radius  # rad/s
        self.ticks_at_top_speed = (
            top_wheel_speed * env.unwrapped.dt * cfg.encoders.ticks_per_rev / (2 * math.pi)
        )
        self.map_view: MapView | None = None  # built at each reset, when the config asks
        size = 2 * len(self.config.lookahead) + 9 + cfg.sonar.count + 2
        size += BOARD_FEATURES * config.boards + (cfg.sonar.count if config.predicted_sonar else 0)
        self._proposal = PROPOSAL in env.observation_space.spaces
        size += 3 if self._proposal else 0
        self.observation_space = spaces.Box(-FEATURE_LIMIT, FEATURE_LIMIT, (size,), np.float32)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Reset the env: the policy's flat input of the episode's path
        (:meth:`follow_path`), and ``info["is_success"]`` False."""
        obs, info = self.env.reset(seed=seed, options=options)
        self.follow_path(info)
        return self.observation(obs), {**info, "is_success": False}

    def follow_path(self, info: Mapping[str, Any]) -> None:
        """Take the episode's path from a reset's ``info["path"]`` (a generated world brings a
        new one), and the map of its world when the config reads it."""
        self.path = Polyline(info["path"])
        uses_map = self.config.boards or self.config.predicted_sonar
        self.map_view = MapView(self.env, self.config.scale) if uses_map else None

    def step(self, action):
        """Step the env: the policy's flat input, and ``info["is_success"]``, True only at the
        end of an episode that reached every goal."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        info["is_success"] = bool((terminated or truncated) and info["success"])
        return self.observation(obs), reward, terminated, truncated, info

    def observation(self, obs: dict) -> np.ndarray:
        """The policy's input (:attr:`observation_space`) from the wrapped env's observation."""
        x, y, yaw = (float(v) for v in obs["pose"])
        c, s = math.cos(yaw), math.sin(yaw)
        to_robot = np.array([[c, s], [-s, c]])
        here = self.path.project((x, y))
        ahead = np.array([self.path.point_at(here + d) for d in self.config.lookahead])
        points = (ahead - (x, y)) @ to_robot.T / self.config.scale
        end = min(here + TANGENT_STEP, self.path.length)
        dx, dy = self.path.point_at(end) - self.path.point_at(end - TANGENT_STEP)
        heading_error = math.atan2(dy, dx) - yaw
        cov = np.asarray(obs["pose_cov"], dtype=float).reshape(3, 3)
        position_var = np.diag(to_robot @ cov[:2, :2] @ to_robot.T)
        stds = np.sqrt(np.maximum([*position_var, cov[2, 2]], 0.0))
        low, high = self.sonar_range
        goal = (np.asarray(obs["goal"], dtype=float) - (x, y)) @ to_robot.T
        left = float(obs["goal_arc"][0]) - here
        horizon = self.config.goal_horizon
        if horizon is not None and self.config.far_goal == "route" and left > horizon:
            goal = (self.path.point_at(here + horizon) - (x, y)) @ to_robot.T
            left = horizon
        elif horizon is not None:
            left = min(left, horizon)
            goal *= min(1.0, horizon / max(float(np.hypot(*goal)), 1e-9))
        features = np.concatenate(
            [
                points.ravel(),
                [left / self.config.scale],
                goal / self.config.scale,
                [int(obs["goals_left"][0]) / int(obs["goal_count"][0])],
                [math.sin(heading_error), math.cos(heading_error)],
                np.log10(np.clip(stds, STD_FLOOR, STD_CEIL)) / 3.0,
                (np.asarray(obs["sonar"], dtype=float) - low) / (high - low),
                np.asarray(obs["encoders"], dtype=float) / self.ticks_at_top_speed,
                *self._map_features(obs["pose"]),
                *([obs[PROPOSAL]] if self._proposal else []),
            ]
        )
        return np.clip(features, -FEATURE_LIMIT, FEATURE_LIMIT).astype(np.float32)

    def _map_features(self, pose: np.ndarray) -> list[np.ndarray]:
        """The map's entries of the input (none unless the config asks for them)."""
        if self.map_view is None:
            return []
        boards = [self.map_view.boards(pose, self.config.boards)] if self.config.boards else []
        return boards + ([self.map_view.sonar(pose)] if self.config.predicted_sonar else [])
