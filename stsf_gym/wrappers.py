"""``PoseEstimateWrapper``: adds a pose estimate and its covariance to the observation.

The wrapper is the one seam between the simulator and the estimators: :func:`sensor_model`
turns an env into the :class:`SensorModel` an estimator runs on.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from stsf_gym.estimators import (
    ESTIMATORS,
    PRIVILEGED,
    MapLandmark,
    PoseEstimator,
    SensorModel,
    estimator_class,
    estimator_settings,
    make_estimator,
)
from stsf_gym.estimators.base import SonarRingModel
from stsf_gym.estimators.camera_pointing import LandmarkPointer
from stsf_gym.estimators.odometry import OdometryNoise
from stsf_gym.estimators.settings import OdometrySettings
from stsf_gym.geometry import bounded
from stsf_gym.state_history import EstimatorDriver, history_horizon
from stsf_gym.validation import ConfigError, reset_options

#: Default standard deviations of the start pose the robot is given (m, m, rad).
START_STD = (0.01, 0.01, 0.005)
COV_LIMIT = 1e4
#: With an unknown start the pan camera sweeps (a sine of this period, s) until the estimate's
#: position standard deviation first falls below ``FOUND_STD`` (m) with a map board confirming
#: it (the estimator's ``confirmed``, where it has one): pointed from a pose that is not known
#: yet, it would look at walls, and the sonar alone can settle on the wrong end of a corridor.
SWEEP_PERIOD_S, FOUND_STD = 4.0, 0.2
#: The privileged pose source: the true pose from ``info``, for reference runs only.
TRUTH = "truth"
#: Standard deviations (m, m, rad) reported with the true pose: tiny, fixed.
TRUTH_STD = (0.001, 0.001, 0.001)
#: Every pose source a wrapper accepts: the estimators, the privileged ``truth`` and the
#: privileged ``degraded-truth`` (the accuracy curve's dial).
POSE_SOURCES = (*ESTIMATORS, TRUTH, *PRIVILEGED)


def check_pose_source(name: str) -> None:
    """Fail (:class:`ConfigError`) unless ``name`` is a pose source: one of
    :data:`POSE_SOURCES`, a registered estimator or a ``package.module:Class`` estimator."""
    if name != TRUTH:
        estimator_class(name)


def _as_json(value: Any) -> Any:
    """``value`` with its tuples and arrays as lists and numpy scalars as numbers, as a JSON
    round trip gives it back."""
    if isinstance(value, dict):
        return {key: _as_json(item) for key, item in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [_as_json(item) for item in value]
    return value.item() if isinstance(value, np.generic) else value


def sensor_model(env: gym.Env, belief: OdometrySettings | None = None) -> SensorModel:
    """The model of ``env``'s robot for the current episode (call after each reset): its
    believed odometry calibration, believed camera calibration, mount and landmark map (never
    the true camera: ``camera_matrix`` and ``dist_coeffs`` are for evaluation), and the noise
    the estimator ``belief`` assumes (default: the nominal ``configs/estimators/odometry.yaml``),
    never the env's true noise settings."""
    u = env.unwrapped
    cfg = u.config
    belief = belief or estimator_settings("odometry")
    calibration = u.odometry_calibration
    return SensorModel(
        calibration=calibration,
        odometry_noise=OdometryNoise.from_encoders(
            belief.slip_std,
            belief.radius_error_std,
            belief.wheelbase_error_std,
            (calibration.wheel_radius_left + calibration.wheel_radius_right) / 2,
        ),
        camera_calibration=u.camera_calibration,
        camera_calibration_std=(
            belief.principal_point_std_px / u.camera_calibration.K[0, 0],
            belief.focal_std,
        ),
        camera_matrix=u.camera_calibration.K,
        image_size=(cfg.camera.width, cfg.camera.height),
        robot_from_camera=u.camera_mount,
        landmarks={
            lm.id: MapLandmark(lm.id, lm.centre, lm.normal, lm.square_centres) for lm in u.landmarks
        },
        pattern=cfg.world.landmark_pattern,
        walls=np.array(cfg.world.walls, dtype=float).reshape(-1, 4),
        wall_thickness=cfg.world.wall_thickness,
        sonar=SonarRingModel(
            axes=np.asarray(u.sonar.axes, dtype=float),
            ring_radius=u.sonar.origin_radius,
            min_range=cfg.sonar.min_range,
            max_range=cfg.sonar.max_range,
            noise_std=cfg.sonar.noise_std,
            noise_std_per_m=cfg.sonar.noise_std_per_m,
        ),
        body_radius=cfg.robot.body_radius,
    )


class EstimateError(ValueError):
    """A pose source returned what no pose estimate can be: a pose that is not three finite
    numbers, or a covariance that is not a symmetric positive definite 3x3 matrix."""


#: How far a covariance may be from symmetric, relative to its largest entry (rounding).
SYMMETRY_TOLERANCE = 1e-6


def check_estimate(name: str, mean: Any, cov: Any) -> tuple[np.ndarray, np.ndarray]:
    """``mean`` and ``cov`` as float arrays if they are a pose estimate, else an
    :class:`EstimateError` naming pose source ``name`` (checked at every step it returns, on
    plain floats: a 3x3 check costs more in numpy's call overhead than in arithmetic)."""
    mean, cov = np.asarray(mean, dtype=float), np.asarray(cov, dtype=float)
    where = f"pose source {name!r} returned"
    if mean.shape != (3,) or not all(map(math.isfinite, mean.tolist())):
        raise EstimateError(f"{where} the pose {mean.tolist()}: not three finite numbers x, y, yaw")
    entries = cov.ravel().tolist()
    if cov.shape != (3, 3) or not all(map(math.isfinite, entries)):
        raise EstimateError(f"{where} the covariance {cov.tolist()}: not a finite 3x3 matrix")
    scale = max(map(abs, entries))
    asymmetry = max(abs(entries[i] - entries[j]) for i, j in ((1, 3), (2, 6), (5, 7)))
    if asymmetry > SYMMETRY_TOLERANCE * scale:
        raise EstimateError(f"{where} the covariance {cov.tolist()}: not symmetric")
    if not _cholesky_succeeds(entries):
        eigenvalues = np.linalg.eigvalsh(cov).tolist()
        raise EstimateError(
            f"{where} the covariance {cov.tolist()}: not positive definite (eigenvalues "
            f"{eigenvalues}); NEES and the agent's uncertainty need a positive definite one"
        )
    return mean, cov


def _cholesky_succeeds(c: list[float]) -> bool:
    """Whether the Cholesky factorization ``L L^T`` of the symmetric 3x3 matrix ``c`` (row
    major; its lower triangle read, as ``np.linalg.cholesky`` does) exists: every pivot > 0."""
    if not c[0] > 0:
        return False
    l00 = math.sqrt(c[0])
    l10, l20 = c[3] / l00, c[6] / l00
    pivot = c[4] - l10 * l10
    if not pivot > 0:
        return False
    l21 = (c[7] - l20 * l10) / math.sqrt(pivot)
    return c[8] - l20 * l20 - l21 * l21 > 0


def check_sensors(name: str, sensors: tuple[str, ...], camera_enabled: bool) -> None:
    """Refuse pose source ``name`` (reading ``sensors``) on an env whose camera is off."""
    if "camera" in sensors and not camera_enabled:
        raise ConfigError(
            f"pose source {name!r} reads the camera, but camera.enabled is false; switch it on "
            "(camera.mode: fast simulates detections without rendering)",
            "camera.enabled",
        )


def estimator_driver(
    name: str, estimator: PoseEstimator, delay_s: float, jitter_s: float, control_dt: float
) -> EstimatorDriver:
    """The driver of pose source ``name``: through a history of late frames when the camera
    has a latency (``delay_s``, ``jitter_s``), unless the source is privileged."""
    privileged = name in (TRUTH, *PRIVILEGED)
    horizon = None if privileged else history_horizon(delay_s, jitter_s, control_dt)
    return EstimatorDriver(estimator, horizon)


class TruePose(PoseEstimator):
    """The privileged reference "estimator": the true pose with a tiny fixed covariance.

    Not an estimator: the wrapper hands it ``info["true_pose"]`` (:meth:`see`), the one place
    where ``info`` feeds a pose. It gives agents trained or run on perfect localization, to
    compare the real estimators against.
    """

    name = TRUTH
    sensors = ()

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        """Start at the true pose with the fixed :data:`TRUTH_STD` covariance."""
        super().reset(model, initial_pose, np.diag(np.square(TRUTH_STD)))

    def see(self, true_pose: np.ndarray) -> None:
        """Take the true pose of the step (from ``info``)."""
        self.mean = np.asarray(true_pose, dtype=float).copy()

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        return self.mean, self.cov


class PoseEstimateWrapper(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Runs a pose estimator on every observation and adds

    - ``obs["pose"]``: ``Box((3,), float32)``, the estimate ``[x, y, yaw]`` (world frame);
    - ``obs["pose_cov"]``: ``Box((9,), float32)``, its 3x3 covariance flattened row by row
      (``obs["pose_cov"].reshape(3, 3)``; entries clipped to +-1e4). Flat, so SB3's
      multi-input policies take it as it is.

    The estimator's ``dt`` is the time between the encoders' timestamps. When the camera has
    a latency (``camera.latency``), a late frame is fused at its exposure time: the estimator
    is rewound and the odometry since replayed
    (:class:`~stsf_gym.state_history.EstimatorDriver`, which a log's replay runs too; so
    ``wrapper.estimator`` may be a new object after a step).

    With ``estimator="truth"`` the pose is the true one from ``info`` (:class:`TruePose`):
    privileged, for reference runs only; ``"degraded-truth"`` corrupts it with a configurable
    error model (:mod:`stsf_gym.estimators.degraded_truth`), seeded by ``reset(seed=...)``.
    The real estimators never see ``info``: each starts an episode at the commanded start
    pose (``options["start_pose"]``, the one drawn from ``task.start_*`` or the world's ``start``;
    ``env.unwrapped.start_pose``) with standard deviations
    ``start_std``; ``reset(options={"unknown_start": True})`` gives an estimator that
    localizes globally (``mcl``) no start at all: its prior spreads over the map's free space.
    When the env's camera has a pan axis (``camera.control: pan``), the wrapper points it at a
    landmark from the pose estimate and the map (:class:`LandmarkPointer`) and the agent's
    action has no pan entry (``action_layout``: ``[v, w]``, or ``[v, w, stop]``).

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
        if estimator == TRUTH and options:
            raise ConfigError(f"the truth pose source takes no options, got {sorted(options)}")
        source = TruePose() if estimator == TRUTH else make_estimator(estimator, **options)
        latency = env.unwrapped.config.camera.latency
        self.driver = estimator_driver(
            estimator, source, latency.delay_s, latency.jitter_s, env.unwrapped.dt
        )
        self.pose_source = estimator  # the name errors give it
        check_sensors(estimator, source.sensors, env.unwrapped.config.camera.enabled)
        robot = env.unwrapped.config.robot
        self.pointer = None
        #: the agent's action entries (:class:`~stsf_gym.envs.action_layout.ActionLayout`)
        self.action_layout = env.unwrapped.action_layout
        if env.unwrapped.config.camera.control == "pan":
            # the wrapper points the camera; the agent's action has no pan entry
            self.pointer = LandmarkPointer(
                {}, np.zeros((0, 4)), robot.camera_forward, math.radians(robot.pan_limit_deg)
            )
            self.action_layout = self.action_layout.without("pan")
            self.action_space = self.action_layout.space
        self.start_cov = np.diag(np.square(np.asarray(start_std, dtype=float)))
        self.start, self.searching_since = None, None  # set by reset
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

    @property
    def estimator(self) -> PoseEstimator:
        """The live pose estimator (a new object after a late frame rewound it)."""
        return self.driver.estimator

    def reset(self, *, seed=None, options=None):
        """Reset the env and start the estimator at the commanded start pose; ``options`` as
        the env's, plus ``unknown_start`` (an estimator that localizes globally: ``mcl``)."""
        options = reset_options(options)
        unknown_start = bool(options.pop("unknown_start", False))  # the wrapper's, not the env's
        obs, info = self.env.reset(seed=seed, options=options or None)
        start = self.env.unwrapped.start_pose  # where the env put the robot (start_pose option,
        self.start = np.asarray(start, dtype=float)  # drawn or the world's); a floor starts there
        settings = getattr(self.estimator, "settings", None)
        model = sensor_model(self.env, settings if isinstance(settings, OdometrySettings) else None)
        if hasattr(self.estimator, "seed"):  # a privileged source with its own random draws
            self.estimator.seed(seed)
        self.estimator.reset(model, start, self.start_cov)
        self.searching_since = None
        if unknown_start:
            self._forget_start()
            self.searching_since = 0.0
        self._time = float(obs["encoders_time"][0])
        self.driver.start(obs, info["true_pose"])
        if self.pointer is not None:
            self.pointer.landmarks, self.pointer.walls = model.landmarks, model.walls
            self.pointer.reset()
        return self._with_pose(obs, self.estimator.mean, self.estimator.cov), info

    @property
    def searching(self) -> bool:
        """An unknown start not localized yet (the pan camera sweeps): an agent should not
        trust the pose (:meth:`~stsf_gym.agents.follower.PathFollower.explore`)."""
        return self.searching_since is not None

    def _forget_start(self) -> None:
        spread = getattr(self.estimator, "spread_prior", None)
        if spread is None:
            raise ConfigError(
                f"reset option unknown_start needs an estimator that localizes globally "
                f"(mcl), not {self.estimator.name or type(self.estimator).__name__!r}"
            )
        spread()

    def step(self, action):
        """Point the camera (pan mount), step the env, update the estimate from the observation."""
        if self.searching_since is not None:
            cov = self.estimator.cov
            narrow = math.sqrt(max(cov[0, 0], cov[1, 1])) < FOUND_STD
            if narrow and getattr(self.estimator, "confirmed", True):
                self.searching_since = None
            else:
                self.searching_since += self.env.unwrapped.dt
        if self.pointer is not None:
            if self.searching_since is not None:
                pan = math.sin(math.tau * self.searching_since / SWEEP_PERIOD_S)
            else:
                pan = self.pointer.pan(self.estimator.mean) / self.pointer.pan_limit
            action = self.env.unwrapped.action_layout.fill(action, self.action_layout, pan=pan)
        obs, reward, terminated, truncated, info = self.env.step(action)
        time = float(obs["encoders_time"][0])
        dt, self._time = time - self._time, time  # from the sensors' timestamps
        mean, cov = self.driver.update(obs, dt, info["true_pose"])
        return self._with_pose(obs, mean, cov), reward, terminated, truncated, info

    def _with_pose(self, obs: dict, mean: np.ndarray, cov: np.ndarray) -> dict:
        mean, cov = check_estimate(self.pose_source, mean, cov)
        view = self.env.unwrapped.view  # the env's map (render_mode set) draws the estimate
        if view is not None:
            target = None if self.pointer is None else self.pointer.target
            view.show_estimate(self.estimator.name, mean, cov, target)
        pose = np.array([mean[0], mean[1], np.arctan2(np.sin(mean[2]), np.cos(mean[2]))])
        low, high = self.observation_space["pose"].low, self.observation_space["pose"].high
        return {
            **obs,
            "pose": bounded(pose, low, high).astype(np.float32),
            "pose_cov": bounded(cov, -COV_LIMIT, COV_LIMIT).astype(np.float32).ravel(),
        }
