"""``PoseEstimateWrapper``: adds a pose estimate and its covariance to the observation."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from stsf_gym.estimators import SensorModel, make_estimator
from stsf_gym.estimators.camera_pointing import LandmarkPointer

#: Default standard deviations of the start pose the robot is given (m, m, rad).
START_STD = (0.01, 0.01, 0.005)
COV_LIMIT = 1e4


class PoseEstimateWrapper(gym.Wrapper):
    """Runs a pose estimator on every observation and adds

    - ``obs["pose"]``: ``Box((3,), float32)``, the estimate ``[x, y, yaw]`` (world frame);
    - ``obs["pose_cov"]``: ``Box((9,), float32)``, its 3x3 covariance flattened row by row
      (``obs["pose_cov"].reshape(3, 3)``; entries clipped to +-1e4). Flat, so SB3's
      multi-input policies take it as it is.

    The estimator starts each episode at the commanded start pose (the world's ``start`` or
    ``options["start_pose"]``) with standard deviations ``start_std``; it never sees ``info``.
    When the env's camera has a pan axis (``camera.control: pan``), the wrapper points it at a
    landmark from the pose estimate and the map (:class:`LandmarkPointer`) and the agent's
    action stays ``[v, w]``.

    Args:
        env: a stsf-gym env.
        estimator: ``"odometry"``, ... (see :data:`stsf_gym.estimators.ESTIMATORS`).
        start_std: standard deviations of the start pose (m, m, rad).
        **options: estimator options, over ``configs/estimators/<name>.yaml``.
    """

    def __init__(self, env: gym.Env, estimator: str = "odometry", start_std=START_STD, **options):
        super().__init__(env)
        self.estimator = make_estimator(estimator, **options)
        robot = env.unwrapped.config.robot
        self.pointer = None
        if env.unwrapped.config.camera.control == "pan":
            # the wrapper points the camera; the agent keeps the (v, w) action
            self.pointer = LandmarkPointer(
                {}, np.zeros((0, 4)), robot.camera_forward, math.radians(robot.pan_limit_deg)
            )
            self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.start_cov = np.diag(np.square(np.asarray(start_std, dtype=float)))
        lo, hi = env.unwrapped.world.bounds[0] - 50.0, env.unwrapped.world.bounds[1] + 50.0
        pose_space = spaces.Box(
            np.array([lo[0], lo[1], -np.pi], np.float32),
            np.array([hi[0], hi[1], np.pi], np.float32),
            dtype=np.float32,
        )
        cov_space = spaces.Box(-COV_LIMIT, COV_LIMIT, (9,), np.float32)
        self.observation_space = spaces.Dict(
            {**env.observation_space.spaces, "pose": pose_space, "pose_cov": cov_space}
        )

    def reset(self, *, seed=None, options=None):
        obs, info = self.env.reset(seed=seed, options=options)
        start = (options or {}).get("start_pose", self.env.unwrapped.config.world.start)
        model = SensorModel.from_env(self.env)
        self.estimator.reset(model, start, self.start_cov)
        if self.pointer is not None:
            self.pointer.landmarks, self.pointer.walls = model.landmarks, model.walls
            self.pointer.reset()
        return self._with_pose(obs, self.estimator.mean, self.estimator.cov), info

    def step(self, action):
        if self.pointer is not None:
            pan = self.pointer.pan(self.estimator.mean) / self.pointer.pan_limit
            action = np.append(np.asarray(action, dtype=np.float32).ravel(), np.float32(pan))
        obs, reward, terminated, truncated, info = self.env.step(action)
        mean, cov = self.estimator.update(obs, self.env.unwrapped.dt)
        return self._with_pose(obs, mean, cov), reward, terminated, truncated, info

    def _with_pose(self, obs: dict, mean: np.ndarray, cov: np.ndarray) -> dict:
        pose = np.array([mean[0], mean[1], np.arctan2(np.sin(mean[2]), np.cos(mean[2]))])
        low, high = self.observation_space["pose"].low, self.observation_space["pose"].high
        return {
            **obs,
            "pose": np.clip(pose, low, high).astype(np.float32),
            "pose_cov": np.clip(cov, -COV_LIMIT, COV_LIMIT).astype(np.float32).ravel(),
        }


def make_estimating_env(estimator: str, **env_kwargs) -> gym.Env:
    """Entry point of the registered ``stsf_gym/<World>-<Estimator>-v0`` ids."""
    from envs.corridor_env import CorridorEnv

    estimator_options = env_kwargs.pop("estimator_options", {})
    return PoseEstimateWrapper(CorridorEnv(**env_kwargs), estimator, **estimator_options)
