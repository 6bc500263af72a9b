"""``PoseEstimateWrapper``: adds a pose estimate and its covariance to the observation, and
nothing else (the camera's pointing is :mod:`stsf_gym.wrappers.pointing`'s)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from stsf_gym.estimators import PoseEstimator, make_estimator
from stsf_gym.geometry import bounded
from stsf_gym.validation import ConfigError, reset_options
from stsf_gym.wrappers.pose_sources import (
    TRUTH,
    TruePose,
    check_estimate,
    check_sensors,
    estimator_driver,
)
from stsf_gym.wrappers.sensor_model import sensor_model

#: Default standard deviations of the start pose the robot is given (m, m, rad).
START_STD = (0.01, 0.01, 0.005)
COV_LIMIT = 1e4


def _as_json(value: Any) -> Any:
    """``value`` with its tuples and arrays as lists and numpy scalars as numbers, as a JSON
    round trip gives it back."""
    if isinstance(value, dict):
        return {key: _as_json(item) for key, item in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [_as_json(item) for item in value]
    return value.item() if isinstance(value, np.generic) else value


class PoseEstimateWrapper(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Runs a pose estimator on every observation and adds

    - ``obs["pose"]``: ``Box((3,), float32)``, the estimate ``[x, y, yaw]`` (world frame);
    - ``obs["pose_cov"]``: ``Box((9,), float32)``, its 3x3 covariance flattened row by row
      (``obs["pose_cov"].reshape(3, 3)``; entries clipped to +-1e4). Flat, so SB3's
      multi-input policies take it as it is.

    The action space and the camera are left as they are; a pan camera is pointed by
    :class:`~stsf_gym.wrappers.pointing.CameraPointingWrapper` over this wrapper. The env's map
    view (``render_mode`` set) asks the wrapper for its estimate at each frame it draws
    (``draw_on_map``).

    The estimator's ``dt`` is the time between the encoders' timestamps. When the camera has
    a latency (``camera.latency``), a late frame is fused at its exposure time: the estimator
    is rewound and the odometry since replayed
    (:class:`~stsf_gym.wrappers.state_history.EstimatorDriver`, which a log's replay runs too; so
    ``wrapper.estimator`` may be a new object after a step).

    With ``estimator="truth"`` the pose is the true one from ``info`` (:class:`TruePose`):
    privileged, for reference runs only; ``"degraded-truth"`` corrupts it with a configurable
    error model (:mod:`stsf_gym.estimators.degraded_truth`), seeded by ``reset(seed=...)``.
    The real estimators never see ``info``: each starts an episode at the commanded start
    pose (``options["start_pose"]``, the one drawn from ``task.start_*`` or the world's ``start``;
    ``env.unwrapped.start_pose``) with standard deviations
    ``start_std``; ``reset(options={"unknown_start": True})`` gives an estimator that
    localizes globally (``mcl``) no start at all: its prior spreads over the map's free space.

    Args:
        env: a stsf-gym env.
        estimator: ``"odometry"``, ... (see :data:`stsf_gym.estimators.ESTIMATORS`), a
            ``package.module:Class`` estimator of your own, or ``"truth"`` (privileged).
        start_std: standard deviations of the start pose (m, m, rad).
        **options: estimator options, over ``configs/estimators/<name>.yaml`` (your own
            estimator: over its settings dataclass's defaults).

    Its constructor arguments are recorded (``RecordConstructorArgs``), so ``env.spec``
    re-creates a hand-built stack: ``gym.make(env.spec)``.
    """

    def __init__(self, env: gym.Env, estimator: str = "odometry", start_std=START_STD, **options):
        gym.utils.RecordConstructorArgs.__init__(  # as JSON reads them: spec.to_json round trips
            self, estimator=estimator, **_as_json({"start_std": start_std, **options})
        )
        gym.Wrapper.__init__(self, env)
        held = [key for key in ("pose", "pose_cov") if key in env.observation_space.spaces]
        if held:
            below = (
                env.get_wrapper_attr("pose_source") if env.has_wrapper_attr("pose_source") else "?"
            )
            raise ValueError(
                f"PoseEstimateWrapper({estimator!r}) over an observation that has {held[0]!r} "
                f"already (pose source {below!r}): one pose estimate per env; make the env "
                "without an estimate (e.g. stsf_gym/Corridor-v0) or pick that id's pose source"
            )
        if estimator == TRUTH and options:
            raise ConfigError(f"the truth pose source takes no options, got {sorted(options)}")
        source = TruePose() if estimator == TRUTH else make_estimator(estimator, **options)
        corridor = env.unwrapped
        latency = corridor.config.camera.latency
        self.driver = estimator_driver(source, latency.delay_s, latency.jitter_s, corridor.dt)
        self.pose_source = estimator  # the name errors give it
        check_sensors(estimator, source.sensors, corridor.config.camera.enabled)
        self.start_cov = np.diag(np.square(np.asarray(start_std, dtype=float)))
        self.start = None  # set by reset
        self._drawn: tuple[np.ndarray, np.ndarray] | None = None  # the map's estimate
        lo, hi = corridor.world.bounds[0] - 50.0, corridor.world.bounds[1] + 50.0
        pose_space = spaces.Box(
            np.array([lo[0], lo[1], -np.pi], np.float32),
            np.array([hi[0], hi[1], np.pi], np.float32),
            dtype=np.float32,
        )
        cov_space = spaces.Box(-COV_LIMIT, COV_LIMIT, (9,), np.float32)
        self.observation_space = spaces.Dict(
            {**env.observation_space.spaces, "pose": pose_space, "pose_cov": cov_space}
        )
        corridor.draw_on_map(self._map_marks)

    @property
    def estimator(self) -> PoseEstimator:
        """The live pose estimator (a new object after a late frame rewound it)."""
        return self.driver.estimator

    def reset(self, *, seed=None, options=None):
        """Reset the env and start the estimator at the commanded start pose; ``options`` as
        the env's, plus ``unknown_start`` (an estimator that localizes globally: ``mcl``)."""
        options = reset_options(options)
        unknown_start = bool(options.pop("unknown_start", False))  # the wrapper's, not the env's
        self._drawn = None  # nothing to draw until this episode's first estimate
        obs, info = self.env.reset(seed=seed, options=options or None)
        start = self.env.unwrapped.start_pose  # where the env put the robot (start_pose option,
        self.start = np.asarray(start, dtype=float)  # drawn or the world's); a floor starts there
        model = sensor_model(self.env, self.estimator.believed_odometry())
        self.estimator.seed(seed)  # a source with its own random draws (mcl, degraded-truth)
        self.estimator.reset(model, start, self.start_cov)
        if unknown_start:
            self.estimator.spread_prior()  # refused unless it localizes globally
        self._time = float(obs["encoders_time"][0])
        self.driver.start(obs, info["true_pose"])
        return self._with_pose(obs, self.estimator.mean, self.estimator.cov), info

    def step(self, action):
        """Step the env, update the estimate from the observation."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        time = float(obs["encoders_time"][0])
        dt, self._time = time - self._time, time  # from the sensors' timestamps
        mean, cov = self.driver.update(obs, dt, info["true_pose"])
        return self._with_pose(obs, mean, cov), reward, terminated, truncated, info

    def _with_pose(self, obs: dict, mean: np.ndarray, cov: np.ndarray) -> dict:
        mean, cov = check_estimate(self.pose_source, mean, cov)
        self._drawn = mean, cov
        pose = np.array([mean[0], mean[1], np.arctan2(np.sin(mean[2]), np.cos(mean[2]))])
        low, high = self.observation_space["pose"].low, self.observation_space["pose"].high
        return {
            **obs,
            "pose": bounded(pose, low, high).astype(np.float32),
            "pose_cov": bounded(cov, -COV_LIMIT, COV_LIMIT).astype(np.float32).ravel(),
        }

    def _map_marks(self) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], tuple[int, ...]]:
        """What the env's map view draws of this wrapper (it asks at each frame): the last
        estimate under the estimator's name (none before this episode's first)."""
        return {} if self._drawn is None else {self.estimator.name: self._drawn}, ()
