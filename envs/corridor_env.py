"""The Gymnasium environment: a differential-drive robot in a PyBullet corridor."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from stsf_gym.camera_model import CameraCalibration, PanTiltMount
from stsf_gym.envs.action_layout import ActionLayout, numeric_action
from stsf_gym.envs.config import EnvConfig, WorldConfig, check_env_keywords, load_config
from stsf_gym.envs.drive_controller import VelocityController
from stsf_gym.envs.faults import FaultInjector
from stsf_gym.envs.random_streams import RandomStreams
from stsf_gym.envs.rendering.map_view import MapMarks, MapView, detections_frame
from stsf_gym.envs.rendering.window import HumanWindow, display_available
from stsf_gym.envs.robot import DiffDriveRobot
from stsf_gym.envs.sensors.camera import PinholeCamera, believed_calibration, look_at, view_matrix
from stsf_gym.envs.sensors.camera_timing import FrameQueue
from stsf_gym.envs.sensors.encoders import WheelEncoders
from stsf_gym.envs.sensors.fast_camera import SimulatedDetector
from stsf_gym.envs.sensors.rendered_camera import RenderedCamera
from stsf_gym.envs.sensors.sonar import SonarRing
from stsf_gym.envs.sensors.sonar_firing import FiringSchedule
from stsf_gym.envs.simulator import Simulator
from stsf_gym.envs.start_pose import draw_leg, draw_start_pose, legs
from stsf_gym.envs.step_info import stop_info
from stsf_gym.envs.task import PathTask
from stsf_gym.envs.worlds.corridor import CorridorWorld, Landmark
from stsf_gym.envs.worlds.geodesic import connected_to_path
from stsf_gym.envs.worlds.spec import check_start_pose
from stsf_gym.geometry import OdometryCalibration, bounded
from stsf_gym.validation import reset_options

RENDER_VFOV_DEG = 60.0
CHASE_DISTANCE, CHASE_MIN_DISTANCE, CHASE_WALL_GAP, CHASE_HEIGHT = 1.8, 0.3, 0.15, 1.6  # m
EGL_WARMUP_FRAMES = 2
SETTLE_STEPS = 30


class CorridorEnv(gym.Env):
    """Drive a differential-drive robot along a corridor path using camera, sonar and encoders.

    ## Action space
    ``Box(-1, 1, (2,), float32)``: ``[v, w]`` scaled to forward speed ``robot.max_speed`` (m/s)
    and yaw rate ``robot.max_yaw_rate`` (rad/s). With ``camera.control`` set to ``pan`` or
    ``pan_tilt`` one or two more entries set the mount's target angles, scaled to its limits;
    with ``task.stop_action`` a last entry ``stop`` declares arrival when above 0 (Habitat's
    STOP). ``action_layout`` names the entries (:mod:`stsf_gym.envs.action_layout`).
    Entries outside [-1, 1] are clipped to it; NaN or infinite entries, a wrong shape or a
    non-numeric dtype (strings, objects, bools) raise ``ValueError``.

    ## Observation space
    ``Dict``:

    - ``image``: ``Box(0, 255, (H, W, 3), uint8)``, the latest camera frame (default 320x240);
      frames are taken at ``camera.rate_hz`` of simulated time, independent of the control
      period, so between frames the previous one is repeated. The frame is rendered
      (``camera.renderer``) through the lens and sensor of ``camera.profile``
      (:mod:`stsf_gym.envs.sensors.rendered_camera`: distortion, vignetting, defocus, motion blur
      over the exposure, gain and noise).
    - ``image_new``: ``Discrete(2)``, 1 when a camera frame became available during this step
      (or reset): with zero ``camera.latency`` the frame exposed at this step's end; with a
      latency (``camera.latency.profile: paper``: 0.127 s detect + 0.332 s localise, plus
      jitter) one exposed earlier (:mod:`stsf_gym.envs.sensors.camera_timing`).
    - With ``camera.mode: fast`` (no rendering; :mod:`stsf_gym.envs.sensors.fast_camera`) ``image``
    is
      replaced by the frame's simulated detections: ``landmark_ids`` ``Box((L,), int64)``
      (-1 marks an empty slot) and ``landmark_points`` ``Box((L * 2 grid^2,), float32)``, the
      pixels ``x0, y0, x1, y1, ...`` of each detected board's lit squares, slot after slot
      (``reshape(L, -1, 2)``), ``L = camera.fast.max_detections``.
    - ``camera_pan_tilt``: ``Box((2,), float32)``, measured mount angles (rad) of that frame.
    - ``sonar``: ``Box(min_range, max_range, (16,), float32)``, ranges (m), transducer 0
      forward, counter-clockwise.
    - ``encoders``: ``Box((2,), int64)``, wheel tick **deltas** [left, right] since the previous
      step (not cumulative counts); convert with ``env.unwrapped.odometry_calibration``.

    Every sensor's reading carries its time (s of simulated time since reset, ``float64``):

    - ``image_time``: ``Box((1,))``, the exposure time of the frame in ``image`` (or
      ``landmark_ids``/``landmark_points``) and ``camera_pan_tilt``; -1 before any frame is
      available;
    - ``sonar_time``: ``Box((16,))``, when each transducer last fired: all at the step end, or
      one after another in ``sonar.firing_order`` every ``sonar.firing_interval_s``
      (:mod:`stsf_gym.envs.sensors.sonar_firing`), the others keeping their last reading;
    - ``encoders_time``: ``Box((1,))``, the end of the interval the tick deltas cover (the
      step's end).

    The task's public map knowledge (:meth:`stsf_gym.envs.task.PathTask.observation`), as the
    task stands after the step (a goal reached at it is already the next one):

    - ``goal``: ``Box(-1e4, 1e4, (2,), float64)``, the current goal ``[x, y]`` (world frame,
      m): the route's next goal (``declare``), or the path's end (``reach``); the last goal
      once every goal is reached;
    - ``goal_arc``: ``Box(0, 1e9, (1,), float64)``, that goal's arc length along the path (m);
    - ``goals_left``: ``Box(0, 2**31 - 1, (1,), int64)``, the goals still to reach or declare
      (0 once every goal is reached);
    - ``goal_count``: ``Box(0, 2**31 - 1, (1,), int64)``, the goals of this episode's route
      (one on a training leg).

    ## Reward
    ``reward.progress`` per metre gained along the path (``declare``: up to the current goal;
    past it nothing), ``reward.time`` per second,
    ``reward.goal`` on reaching each goal, ``reward.false_stop`` on a stop declared off its goal,
    ``reward.collision`` on a collision (each term: :meth:`stsf_gym.envs.task.PathTask.reward`),
    and
    ``reward.steering_change`` (<= 0, default 0) per unit change of the yaw command ``action[1]``.

    ## Episode end (``task.protocol``, :class:`stsf_gym.envs.task.PathTask`)
    - ``reach`` (default; the paper's **reach-the-goal protocol**, used by Table I, Fig. 10 and
      Fig. 11): terminated as a success when the TRUE position enters the world's
      ``goal_radius`` around the path's end.
    - ``declare`` (**declared arrival**, as Habitat PointNav's STOP): the agent declares that it
      has arrived by standing still (commanded ``|v| < task.stop_speed`` and ``|w| <
      task.stop_yaw_rate``, held ``task.stop_seconds``, after moving). The declaration is a
      success only if the true position is then within ``task.goal_radius`` (0.25 m: one body
      radius, near Habitat's 0.2 m) of the current goal; the goals are the world's ``route`` in
      order (or the path's end), a declared stop at each. A stop outside the radius ends the
      episode as a failure; the truth crossing a goal ends nothing. Standing still keeps the
      ``Box`` action of every agent as it is (no extra entry to learn or to append after the
      camera mount), and is how a real robot ends a delivery.

    Under both, touching a wall or obstacle terminates (a failure); truncated (a failure) after
    ``sim.max_episode_seconds`` of simulated time.

    ## Faults
    The ``faults:`` config section (none by default, :mod:`stsf_gym.envs.faults`) injects timed
    faults: camera blackout, blur and dropped frames, landmarks removed, occluded or faked, sonar
    dropouts and false echoes, encoder spikes, a kidnapped robot.

    ## Info
    ``true_pose`` ([x, y, yaw], privileged: for evaluation only), ``camera_pose`` (4x4
    world-from-camera, OpenCV axes, of the frame in ``image``, at the middle of its exposure),
    ``collision``, ``distance_travelled`` (m, true), ``progress`` (m along the path),
    ``sim_time`` (s), ``goals_reached`` (goals done so far), ``success`` (every goal reached),
    ``stops`` (``declare``: how many stops were declared) and ``last_stop`` (the latest as
    ``{goal, time, position, true_distance_m, success}``, the true distance to the goal it was
    declared for; ``goal`` -1 before the first) and ``path`` (``(N, 2)`` ``float64``, the
    episode's world path, public map knowledge: a wrapper follows a new world's route from the
    reset's): every key keeps its shape and type through an episode, so a recorder stores it
    (:mod:`stsf_gym.envs.step_info`).

    ## Camera
    ``camera_matrix`` (K) and ``dist_coeffs`` (OpenCV ``k1 k2 p1 p2 k3``) are the TRUE camera of
    ``image``, for evaluation; ``camera_calibration`` is what the robot believes (K and
    distortion with this episode's calibration error, drawn at reset), the only calibration an
    estimator may use. ``renderer`` names the renderer in use.

    ## Randomness
    Every draw comes from :attr:`streams` (:mod:`stsf_gym.envs.random_streams`): one generator
    per subsystem (encoders, sonar, camera sensor, detector simulation, calibration, faults,
    world generation, timing), spawned at each reset from a seed drawn from ``np_random``. So
    ``reset(seed=s)`` fixes everything, and the camera's mode, rate or absence leaves the other
    subsystems' draws unchanged (common random numbers for paired comparisons).

    ## Arguments
    - ``world``: world name in ``configs/worlds`` (set by the registered id), path or mapping.
    - ``config``: YAML path or mapping merged over ``configs/default.yaml``.
    - ``render_mode``: ``None``, ``"rgb_array"`` or ``"human"`` (a window; needs a display).
      ``render.view`` picks the picture: ``map`` (default; :mod:`stsf_gym.envs.rendering.map_view`:
      a top-down map with the true pose, the estimates of the wrappers that asked to be drawn
      (:meth:`draw_on_map`), sensors and an inset of the camera frame), ``chase`` (a rendered
      camera behind the robot) or ``top`` (a rendered view of the whole world from above).
    - ``**overrides``: single values, e.g. ``camera__width=640`` or ``camera={"rate_hz": 10}``.

    ``reset(seed=..., options={"start_pose": [x, y, yaw]})`` places the robot elsewhere; with
    ``task.start_along``, ``start_lateral`` or ``start_yaw_deg`` above 0 each episode's start is
    drawn near the path's beginning (:mod:`stsf_gym.envs.start_pose`). ``start_pose`` holds the
    episode's start.
    """

    metadata: ClassVar[dict] = {"render_modes": ["rgb_array", "human"], "render_fps": 10}

    def __init__(
        self,
        world: str | dict | None = None,
        config: str | dict | None = None,
        render_mode: str | None = None,
        **overrides: Any,
    ) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(
                f"render_mode must be None, 'rgb_array' or 'human', got {render_mode!r}"
            )
        check_env_keywords(type(self).__name__, overrides, ("world", "config", "render_mode"))
        self.config: EnvConfig = load_config(config, world=world, **overrides)
        cfg = self.config
        self.render_mode = render_mode
        self.dt = cfg.sim.control_dt
        # "human" only where a window can open (the env checkers try every declared mode)
        modes = self.metadata["render_modes"] if display_available() else ["rgb_array"]
        self.metadata = {**self.metadata, "render_modes": modes, "render_fps": 1.0 / self.dt}
        self._substeps = round(cfg.sim.control_dt * cfg.sim.physics_hz)  # whole (config)
        self._rendered_camera = cfg.camera.enabled and cfg.camera.mode == "rendered"
        renders = self._rendered_camera or (render_mode is not None and cfg.render.view != "map")
        self._window = HumanWindow("stsf-gym", 1.0 / self.dt) if render_mode == "human" else None
        self.sim = Simulator(cfg.sim.physics_hz, cfg.camera.renderer if renders else "none")
        try:
            self.world = CorridorWorld(self.sim, cfg.world)
            self.robot = DiffDriveRobot(self.sim, cfg.robot)
        except Exception:
            self.sim.close()
            raise
        self.camera = PinholeCamera(
            cfg.camera.width,
            cfg.camera.height,
            cfg.camera.vfov_deg,
            cfg.camera.near,
            cfg.camera.far,
            cfg.camera.lens.distortion,
        )
        self.camera_calibration: CameraCalibration = self.camera.calibration
        self.camera_sensor = self._camera_sensor()
        self.sonar = SonarRing(cfg.sonar, cfg.robot.body_radius)
        self.sonar_firing = FiringSchedule(cfg.sonar)
        self.frames = FrameQueue(cfg.camera.latency)
        self.encoders = WheelEncoders(cfg.encoders, cfg.robot.wheel_radius, cfg.robot.wheelbase)
        self.controller = VelocityController(cfg.robot)
        self.action_layout = ActionLayout.for_env(cfg.camera.control, cfg.task.stop_action)
        self.action_space = self.action_layout.space
        self.observation_space = self._observation_space()
        self._initial_state: int | None = None
        #: The top-down map (``render_mode`` set); it draws what the map sources give.
        self.view = None if render_mode is None else self._map_view()
        self._map_sources: list[Callable[[], MapMarks]] = []
        self._build_world(cfg.world)
        if self.sim.renderer == "egl" and self._rendered_camera:
            # The first two EGL frames of a client are shaded differently from all later ones
            # (its shadow state settles); discard them so every episode renders alike.
            for _ in range(EGL_WARMUP_FRAMES):
                self.camera_sensor.radiance(self.robot.camera_pose())
        self._frame_pan_tilt = np.zeros(2, np.float32)
        self._frame_pose = np.eye(4)
        self._last_obs: dict = {}

    def _build_world(self, world: WorldConfig) -> None:
        """Make ``world`` the env's world: its bodies (rebuilt with the robot's from an empty
        simulation when the world changes, and the camera sensor that reads them), the task, the
        faults, and the settled start state every :meth:`reset` restores (a saved state holds
        the bodies that existed when it was saved, so it is saved anew)."""
        if self._initial_state is not None:
            self.sim.client.removeState(self._initial_state)
        if self.world.cfg != world:
            # from an empty simulation, bodies made in the order of a fresh env: the same
            # world then runs bit for bit alike, however many worlds came before it
            self.sim.clear()
            self.world = CorridorWorld(self.sim, world)
            self.robot = DiffDriveRobot(self.sim, self.config.robot)
            self.camera_sensor = self._camera_sensor()
        self.config = dataclasses.replace(self.config, world=world)
        if self.view is not None:  # the map of the new world
            self.view = self._map_view()
        self.task = PathTask(world, self.config.reward, self.config.task)
        self.faults = FaultInjector(
            self.config.faults, self.world, self.robot, self.observation_space
        )
        self._mount_target = np.radians([self.config.camera.pan_deg, self.config.camera.tilt_deg])
        self.robot.reset(world.start, *self._mount_target)
        self.start_pose = np.asarray(world.start, dtype=float)  # each reset sets the episode's
        # Saved after the wheels settled on the floor: the state then holds the contacts too,
        # so each reset starts the solver alike whatever the previous episode did.
        self.sim.step(SETTLE_STEPS)
        self._initial_state = self.sim.client.saveState()

    def _camera_sensor(self) -> SimulatedDetector | RenderedCamera:
        cfg = self.config.camera
        if cfg.mode == "fast":
            return SimulatedDetector(cfg.fast, self.camera, self.world)
        return RenderedCamera(cfg, self.camera, self.sim, self.robot)

    # --- public geometry -------------------------------------------------------------------
    @property
    def camera_matrix(self) -> np.ndarray:
        """The TRUE 3x3 intrinsic matrix K of ``obs["image"]`` (pixel centres at integer
        coordinates): for evaluation only; the robot knows :attr:`camera_calibration`."""
        return self.camera.K

    @property
    def dist_coeffs(self) -> np.ndarray:
        """The TRUE lens distortion of ``obs["image"]``, OpenCV ``k1 k2 p1 p2 k3``:
        for evaluation only."""
        return self.camera.dist

    @property
    def landmarks(self) -> list[Landmark]:
        """Landmark ids and world coordinates of their squares' centres and corners."""
        return self.world.landmarks

    @property
    def renderer(self) -> str:
        """``"gl"``, ``"egl"``, ``"tiny"``, or ``"none"`` (nothing rendered in 3-D: camera off
        or fast, and no render mode or the map view)."""
        return self.sim.renderer

    @property
    def odometry_calibration(self) -> OdometryCalibration:
        """The robot's believed odometry parameters for this episode (not the truth)."""
        return self.encoders.calibration

    def robot_from_camera(self, pan: float, tilt: float) -> np.ndarray:
        """Nominal robot-from-camera 4x4 (OpenCV axes) for mount angles (rad)."""
        return self.robot.robot_from_camera(pan, tilt)

    @property
    def camera_mount(self) -> PanTiltMount:
        """The nominal pan-tilt head of the camera (``camera_mount(pan, tilt)`` is
        :meth:`robot_from_camera`)."""
        return self.robot.mount

    def landmarks_in_view(self, camera_pose: np.ndarray | None = None) -> list[int]:
        """Ids of landmarks wholly inside the frame, facing the camera, present (a fault may
        remove one) and not occluded.

        Uses the true camera pose (``info["camera_pose"]`` by default): for evaluation only.
        """
        pose = self._frame_pose if camera_pose is None else camera_pose
        return self.world.landmarks_in_view(self.camera, pose)

    # --- gymnasium API ----------------------------------------------------------------------
    def _observation_space(self) -> spaces.Dict:
        cfg = self.config
        wheel_rate = (cfg.robot.max_speed + cfg.robot.max_yaw_rate * cfg.robot.wheelbase / 2) / (
            cfg.robot.wheel_radius
        )
        self._max_ticks = math.ceil(
            4 * wheel_rate * self.dt * cfg.encoders.ticks_per_rev / (2 * math.pi)
        )
        limits = np.radians([cfg.robot.pan_limit_deg, cfg.robot.tilt_limit_deg]).astype(np.float32)
        end = cfg.sim.max_episode_seconds + self.dt  # the latest timestamp (s)
        return spaces.Dict(
            {
                **self.camera_sensor.observation_space(),
                "image_new": spaces.Discrete(2),
                "camera_pan_tilt": spaces.Box(-limits - 0.05, limits + 0.05, (2,), np.float32),
                "image_time": spaces.Box(-1.0, end, (1,), np.float64),
                "sonar": spaces.Box(
                    cfg.sonar.min_range, cfg.sonar.max_range, (cfg.sonar.count,), np.float32
                ),
                "sonar_time": spaces.Box(0.0, end, (cfg.sonar.count,), np.float64),
                "encoders": spaces.Box(-self._max_ticks, self._max_ticks, (2,), np.int64),
                "encoders_time": spaces.Box(0.0, end, (1,), np.float64),
                **PathTask.observation_space(),
            }
        )

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode; ``options``: ``start_pose`` ``[x, y, yaw]``, checked as the world's."""
        self.require_open("reset")
        super().reset(seed=seed)
        self.streams = RandomStreams.draw(self.np_random)
        return self._start_episode(options)

    def require_open(self, call: str) -> None:
        """Raise a :class:`RuntimeError` for ``call`` (``step``, ``reset``, ``render``) after
        :meth:`close`."""
        if self.sim.closed:
            raise RuntimeError(f"{call}() after close(): this env is closed; make a new one")

    def _start_episode(self, options: dict | None):
        """Everything of :meth:`reset` after the seed and the episode's :attr:`streams`."""
        options = reset_options(options)
        start = options.pop("start_pose", None)
        given = start is not None
        if options:
            raise ValueError(f"unknown reset option(s) {sorted(options)}; known: ['start_pose']")
        cfg = self.config
        if legs(cfg.task):
            drawn, goal = draw_leg(cfg.world, cfg.task, cfg.robot.body_radius, self.streams.start)
            self.task.set_goals([goal])
            start = drawn if start is None else start
        elif start is None:
            start = draw_start_pose(cfg.world, cfg.task, cfg.robot.body_radius, self.streams.start)
        start = check_start_pose(cfg.world, start, cfg.robot.body_radius, "start_pose")
        if given and not connected_to_path(cfg.world, cfg.robot.body_radius, start[:2]):
            raise ValueError(
                f"start_pose {start.tolist()} is outside the corridor: walls part it from the "
                f"path's start {list(cfg.world.path[0])} (world {cfg.world.name!r})"
            )
        self.start_pose = start  # where the robot was put: the estimators start here
        self.sim.client.restoreState(self._initial_state)
        self._mount_target = np.radians([self.config.camera.pan_deg, self.config.camera.tilt_deg])
        self.robot.reset(tuple(start), *self._mount_target)
        self.faults.reset()
        self.controller.reset()
        streams = self.streams
        self.encoders.reset(self.robot.wheel_angles(), streams.calibration)
        self.camera_calibration = believed_calibration(
            self.camera.calibration, self.config.camera.calibration_error, streams.calibration
        )
        if self.config.camera.enabled:
            self.camera_sensor.reset(self._camera_stream())
        self._time = 0.0
        self._yaw_command = 0.0
        self._distance = 0.0
        self._pose = self.robot.floor_pose()
        self._progress = self.task.progress(self._pose)
        self.task.reset()
        self._next_frame = 0.0
        self.frames.reset()
        self._shown = None  # the frame in the observation (None: none available yet)
        self._camera_obs = self.camera_sensor.observe()  # nothing seen yet
        self._frame_pose = self.robot.camera_pose()
        self._frame_pan_tilt = self.robot.mount_angles().astype(np.float32)
        self.sonar_firing.reset()
        self._sonar_time = np.zeros(self.config.sonar.count)
        if self.sonar_firing.sequential:  # the whole ring's first readings, then the sequence
            self._sonar = self.sonar.read(self.sim, self._pose, streams.sonar)
        obs = self.faults.observe(self._observe(np.zeros(2, np.int64)), 0.0, streams.faults)
        self._last_obs = obs
        if self._window is not None:
            self.render()
        return obs, self._info(collision=False)

    def step(self, action):
        """Apply ``action`` (checked: numeric, finite, of the action space's shape; clipped to
        [-1, 1]) for one control period.
        """
        self.require_open("step")
        a = numeric_action(action).astype(np.float64)
        if a.shape != self.action_space.shape:  # (1, n) of a batch is refused, not flattened
            raise ValueError(f"action must have shape {self.action_space.shape}, got {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"action contains NaN or infinite values: {a.tolist()}")
        a = bounded(a, -1.0, 1.0)
        robot, layout = self.config.robot, self.action_layout
        v, w = a[layout.index("v")] * robot.max_speed, a[layout.index("w")] * robot.max_yaw_rate
        target = np.array([v, w])
        mount = layout.mount(a)
        if len(mount):
            self._mount_target[: len(mount)] = mount * self.robot.pan_tilt_limits[: len(mount)]
            self.robot.point_camera(*self._mount_target)
        if self.faults.before_physics(self._time + self.dt):
            self._pose = self.robot.floor_pose()  # a kidnap is no distance driven
        for substep in range(1, self._substeps + 1):  # the controller runs at the physics rate
            self.robot.drive(*self.controller.update(target, self.sim.time_step))
            self.sim.step(1)
            self._fire_sonars(self._time + substep * self.sim.time_step)
        self._time += self.dt
        pose = self.robot.floor_pose()
        self._distance += float(np.hypot(pose[0] - self._pose[0], pose[1] - self._pose[1]))
        self._pose = pose
        ticks = self.encoders.read(self.robot.wheel_angles(), self.streams.encoders)
        collision = self.robot.in_collision(ignore={self.world.floor})
        progress = self.task.progress(pose)
        reached = self.task.update(pose, v, w, self.dt, self._time, layout.stops(a))
        steering_change = abs(a[layout.index("w")] - self._yaw_command)
        self._yaw_command = float(a[layout.index("w")])
        reward = self.task.reward(
            progress - self._progress, self.dt, reached, collision, steering_change
        )
        self._progress = progress
        terminated = self.task.finished or collision
        truncated = not terminated and self._time >= self.config.sim.max_episode_seconds - 1e-9
        obs = self.faults.observe(self._observe(ticks), self._time, self.streams.faults)
        self._last_obs = obs
        if self._window is not None:
            self.render()
        return obs, float(reward), terminated, truncated, self._info(collision)

    def _fire_sonars(self, time: float) -> None:
        """Transducers of the firing sequence due by ``time`` read the world now."""
        for transducer, fired in self.sonar_firing.due(time):
            pose = self.robot.floor_pose()
            self._sonar[transducer] = self.sonar.read(
                self.sim, pose, self.streams.sonar, np.array([transducer])
            )[0]
            self._sonar_time[transducer] = fired

    def _observe(self, ticks: np.ndarray) -> dict:
        if self._time >= self._next_frame - 1e-9:  # a frame is exposed
            self._next_frame += 1.0 / self.config.camera.rate_hz
            pose = self.robot.camera_pose()
            if self.config.camera.enabled:
                self.camera_sensor.capture(pose, self._camera_stream())
            pan_tilt = self.robot.mount_angles().astype(np.float32)
            camera_obs = self.camera_sensor.observe()
            self.frames.expose(self._time, camera_obs, pose, pan_tilt, self.streams.timing)
        shown = self.frames.release(self._time)
        if shown is not None:
            self._shown, self._camera_obs = shown, shown.camera_obs
            self._frame_pose, self._frame_pan_tilt = shown.pose, shown.pan_tilt
        if not self.sonar_firing.sequential:
            self._sonar = self.sonar.read(self.sim, self._pose, self.streams.sonar)
            self._sonar_time[:] = self._time
        return {
            **{key: value.copy() for key, value in self._camera_obs.items()},
            "image_new": int(shown is not None and self.config.camera.enabled),
            "image_time": np.array([-1.0 if self._shown is None else self._shown.exposure]),
            "camera_pan_tilt": self._frame_pan_tilt.copy(),
            "sonar": self._sonar.copy(),
            "sonar_time": self._sonar_time.copy(),
            "encoders": bounded(ticks, -self._max_ticks, self._max_ticks).astype(np.int64),
            "encoders_time": np.array([self._time]),
            **self.task.observation(),
        }

    def _camera_stream(self) -> np.random.Generator:
        """The rendered camera's sensor noise stream, or the fast mode's detector stream."""
        return (
            self.streams.detector
            if self.config.camera.mode == "fast"
            else (self.streams.camera_sensor)
        )

    def _info(self, collision: bool) -> dict:
        return {
            "true_pose": self._pose.copy(),
            "camera_pose": self._frame_pose.copy(),
            "collision": bool(collision),
            "distance_travelled": float(self._distance),
            "progress": float(self._progress),
            "sim_time": float(self._time),
            "goals_reached": int(self.task.goal_index),
            "success": bool(self.task.success),
            "stops": len(self.task.stops),
            "last_stop": stop_info(self.task.stops),
            "path": np.array(self.config.world.path, dtype=np.float64),
        }

    def render(self):
        """The frame of ``render.view`` (RGB uint8); in ``human`` mode shown, ``None`` returned."""
        self.require_open("render")
        if self.render_mode is None:
            return None
        view = self.config.render.view
        frame = self._map_frame() if view == "map" else self._rendered_view(view)
        if self._window is None:
            return frame
        self._window.show(frame)
        return None

    def draw_on_map(self, source: Callable[[], MapMarks]) -> None:
        """Have the map view ask ``source`` at every frame it draws (sources in the order
        given) for its marks (:data:`~stsf_gym.envs.rendering.map_view.MapMarks`): a wrapper's
        pose estimates ``{label: (mean, cov)}`` and the ids of the landmarks it keeps the camera
        on. The estimates reach the picture this way, by the render path, in every render mode."""
        self._map_sources.append(source)

    def _map_view(self) -> MapView:
        cfg = self.config
        return MapView(
            cfg.world,
            self.world.landmarks,
            cfg.robot.body_radius,
            self.sonar.axes,
            math.radians(cfg.sonar.beam_width_deg) / 2,
            2 * math.atan(cfg.camera.width / (2 * self.camera.focal_px)),  # horizontal FOV
            cfg.render.width,
            cfg.render.height,
        )

    def _map_frame(self) -> np.ndarray:
        obs, camera = self._last_obs, self.config.camera
        inset = None
        if camera.enabled and "image" in obs:
            inset = obs["image"]
        elif camera.enabled and "landmark_ids" in obs:
            inset = detections_frame(
                obs["landmark_ids"], obs["landmark_points"], camera.width, camera.height
            )
        in_view = self.landmarks_in_view() if camera.enabled else []
        return self.view.draw(
            self._pose,
            self._frame_pose if camera.enabled else np.zeros((4, 4)),
            obs.get("sonar"),
            in_view,
            inset,
            f"t = {self._time:.1f} s",
            [source() for source in self._map_sources],
        )

    def _rendered_view(self, view: str) -> np.ndarray:
        cfg = self.config.render
        x, y, yaw = self._pose
        if view == "top":
            centre = self.world.bounds.mean(axis=0)
            extent = np.ptp(self.world.bounds, axis=0) / 2
            half_fov = math.radians(RENDER_VFOV_DEG) / 2
            height = max(extent[1], extent[0] * cfg.height / cfg.width) / math.tan(half_fov)
            pose = look_at([*centre, height], [*centre, 0.0], np.array([0.0, 1.0, 0.0]))
        else:
            heading = np.array([math.cos(yaw), math.sin(yaw), 0.0])
            eye = np.array([x, y, CHASE_HEIGHT]) - self._chase_distance() * heading
            pose = look_at(eye, np.array([x, y, 0.5]) + 1.0 * heading, np.array([0.0, 0.0, 1.0]))
        view_camera = PinholeCamera(cfg.width, cfg.height, RENDER_VFOV_DEG, 0.05, 100.0)
        return self.sim.render_bodies(
            cfg.width, cfg.height, view_matrix(pose), view_camera.projection_matrix()
        )

    def _chase_distance(self) -> float:
        """How far behind the robot the chase camera sits: ``CHASE_DISTANCE``, or closer when
        a wall is nearer, so it always films from inside the corridor."""
        x, y, yaw = self._pose
        back = np.array([x - CHASE_DISTANCE * math.cos(yaw), y - CHASE_DISTANCE * math.sin(yaw)])
        hit = self.sim.client.rayTest([x, y, CHASE_HEIGHT], [*back, CHASE_HEIGHT])[0]
        if hit[0] < 0:
            return CHASE_DISTANCE
        return max(CHASE_MIN_DISTANCE, hit[2] * CHASE_DISTANCE - CHASE_WALL_GAP)

    def close(self) -> None:
        """Close the window (``human`` mode) and disconnect the simulation."""
        if self._window is not None:
            self._window.close()
        self.sim.close()
