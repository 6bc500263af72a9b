"""World and sensor configuration: typed sections loaded from YAML, unknown keys rejected.

Every number lives in ``configs/``: ``configs/default.yaml`` holds the robot, sensors and task,
``configs/worlds/<name>.yaml`` the worlds. :func:`load_config` merges, in order, the defaults,
a user config (YAML path or dict), then keyword overrides, and builds an :class:`EnvConfig`.
Every number has an allowed range (``Annotated[..., Range(...)]``, :mod:`stsf_gym.validation`) and
the world's geometry is checked (:mod:`stsf_gym.envs.worlds.checks`). A misspelt or unknown key, a
value of the wrong type or out of range raises :class:`ConfigError` naming the YAML file that set
it, the full key path and what is allowed: ``configs/x.yaml: robot.wheel_radius must be in
(0, 10], got -0.1``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np

from stsf_gym.camera_model import invertible
from stsf_gym.envs.fault_spec import FaultSpec
from stsf_gym.envs.worlds.checks import (
    check_board_on_wall,
    check_clearance,
    check_route,
    check_world,
)
from stsf_gym.validation import (
    ROBOT_EXTENT_M,
    WORLD_EXTENT_M,
    ConfigError,
    Coordinate,
    Count,
    Degrees,
    KeySources,
    NonNegative,
    Pixels,
    Positive,
    Probability,
    Range,
    RobotLength,
    WorldLength,
    build,
    check_keywords,
    require,
)
from stsf_gym.vision.landmarks import LandmarkPattern
from stsf_gym.yaml_layers import (
    CONFIG_DIR,
    deep_merge,
    overrides_to_tree,
    read_yaml,
    shown,
    world_files,
)

__all__ = [  # re-exported: the config API lives here
    "CONFIG_DIR",
    "ConfigError",
    "EnvConfig",
    "build",
    "deep_merge",
    "load_config",
    "overrides_to_tree",
    "read_yaml",
]


@dataclass(frozen=True)
class LandmarkSpec:
    """One landmark board of a world: its id, where it hangs on a wall and which way it faces."""

    id: Annotated[int, Range(ge=0)]
    at: tuple[Coordinate, Coordinate]  # a point on the wall centre line it hangs on (m)
    facing_deg: Degrees  # world yaw of the landmark's outward normal


@dataclass(frozen=True)
class ObstacleSpec:
    """One clutter obstacle: a box or a cylinder standing on the floor."""

    shape: Literal["box", "cylinder"]
    position: tuple[Coordinate, Coordinate]
    size: tuple[WorldLength, ...]  # box: (length, width, height) / cylinder: (radius, height)
    yaw_deg: Degrees = 0.0


@dataclass(frozen=True)
class WorldConfig:
    """A world (``configs/worlds/*.yaml`` or a generated one): walls, path, start, goal and
    landmarks, checked by :mod:`stsf_gym.envs.worlds.checks`.
    """

    name: str
    walls: tuple[tuple[Coordinate, Coordinate, Coordinate, Coordinate], ...]  # x1, y1, x2, y2
    wall_height: WorldLength
    wall_thickness: WorldLength
    path: tuple[tuple[Coordinate, Coordinate], ...]
    start: tuple[Coordinate, Coordinate, float]
    goal_radius: WorldLength
    landmark_height: Annotated[float, Range(ge=0, le=WORLD_EXTENT_M)]
    landmark_pattern: LandmarkPattern
    landmarks: tuple[LandmarkSpec, ...]
    obstacles: tuple[ObstacleSpec, ...] = ()
    #: goals visited in order, each on the path (the last one its end); empty: the path's end
    route: tuple[tuple[Coordinate, Coordinate], ...] = ()

    def __post_init__(self) -> None:
        require(len(self.walls) > 0, "walls", "must list at least one wall segment")
        require(len(self.path) >= 2, "path", f"must have at least 2 points, got {len(self.path)}")
        check_world(self)
        check_route(self)

    @property
    def goal(self) -> tuple[float, float]:
        return self.path[-1]

    @property
    def goals(self) -> tuple[tuple[float, float], ...]:
        """The goals in visiting order: the route, or the path's end alone."""
        return self.route or (self.path[-1],)


@dataclass(frozen=True)
class SimConfig:
    """The simulation's rates and episode limit (``sim:``)."""

    physics_hz: Positive
    control_dt: Positive
    max_episode_seconds: Positive

    def __post_init__(self) -> None:
        substeps = self.control_dt * self.physics_hz
        require(
            substeps >= 1 - 1e-6 and abs(substeps - round(substeps)) <= 1e-6,
            "control_dt",
            f"must be a whole number of physics steps (1/physics_hz = {1 / self.physics_hz:g} s), "
            f"got {self.control_dt}",
        )
        require(
            self.max_episode_seconds >= self.control_dt,
            "max_episode_seconds",
            f"must be >= control_dt ({self.control_dt}), got {self.max_episode_seconds}",
        )


@dataclass(frozen=True)
class RobotConfig:
    """The robot's body, wheels, drive limits and camera mount (``robot:``)."""

    wheel_radius: RobotLength
    wheelbase: RobotLength
    body_radius: RobotLength
    body_height: RobotLength
    mass: Positive
    wheel_friction: Positive
    wheel_max_torque: Positive
    max_speed: Positive
    max_yaw_rate: Positive
    max_acceleration: Positive  # m/s^2, the wheel velocity controller's linear limit
    max_yaw_acceleration: Positive  # rad/s^2, its angular limit
    nominal_speed: Positive
    camera_height: RobotLength
    camera_forward: Annotated[float, Range(ge=-ROBOT_EXTENT_M, le=ROBOT_EXTENT_M)]
    pan_limit_deg: Annotated[float, Range(ge=0, le=180)]
    tilt_limit_deg: Annotated[float, Range(ge=0, le=90)]

    def __post_init__(self) -> None:
        require(
            self.nominal_speed <= self.max_speed,
            "nominal_speed",
            f"must be <= max_speed ({self.max_speed}), got {self.nominal_speed}",
        )


@dataclass(frozen=True)
class FastCameraConfig:
    """Statistics of the detector, fitted on rendered frames (``benchmarks/fast_sensor_fit.py``)."""

    feature_noise_px: NonNegative  # std of each square centre's pixel error, per axis
    detect_size_px: Positive  # square pitch (px) at which half of the boards are detected
    detect_size_scale: Positive  # logistic width of the detection rate in square pitch (px)
    false_detection_rate: NonNegative  # wrong-id detections per frame
    aided_size_px: Positive  # size (px) at which a track-aided search finds half the missed boards
    aided_size_scale: Positive  # logistic width of that rate (px)
    max_detections: Count  # detection slots in the observation


Relative = Annotated[float, Range(ge=0, lt=0.5)]


@dataclass(frozen=True)
class LensConfig:
    """The lens (:mod:`stsf_gym.envs.sensors.lens`): distortion, vignetting and defocus."""

    distortion: tuple[float, float, float, float, float]  # OpenCV k1 k2 p1 p2 k3
    vignetting: Annotated[float, Range(ge=0, lt=1)]  # share of light lost at the image corner
    defocus_px: NonNegative  # std (px) of the lens's Gaussian point spread; 0 in focus


def radial_reach(distortion: tuple[float, ...], limit: float = 10.0) -> float:
    """The largest distorted radius (normalised image coordinates) that the radial part of
    ``distortion`` (OpenCV k1 k2 p1 p2 k3) reaches while it still grows with the ray's
    radius: the image is invertible up to there. ``limit`` for a lens that never stops."""
    k1, k2, _, _, k3 = distortion
    r = np.linspace(0.0, limit, 20001)
    slope = 1 + 3 * k1 * r**2 + 5 * k2 * r**4 + 7 * k3 * r**6
    stop = int(np.argmax(slope <= 0)) if (slope <= 0).any() else r.size - 1
    radius = r[: stop + 1]
    return float(np.max(radius * (1 + k1 * radius**2 + k2 * radius**4 + k3 * radius**6)))


@dataclass(frozen=True)
class SensorConfig:
    """The image sensor (:mod:`stsf_gym.envs.sensors.image_sensor`): exposure and noise."""

    exposure_s: NonNegative  # exposure time: the camera's motion during it blurs the frame
    gain_std: Relative  # per-frame exposure/gain variation, relative
    read_noise: Annotated[float, Range(ge=0, le=255)]  # std, grey levels
    shot_noise: NonNegative  # photon noise: variance (grey levels^2) per grey level of signal


@dataclass(frozen=True)
class CalibrationErrorConfig:
    """How far the robot's believed camera calibration is from the truth, drawn per episode."""

    focal_std: Relative  # relative error of the focal length
    principal_point_std_px: NonNegative
    distortion_std: tuple[NonNegative, NonNegative, NonNegative, NonNegative, NonNegative]


@dataclass(frozen=True)
class LatencyConfig:
    """Exposure to availability of a camera frame (``configs/latency/<profile>.yaml``)."""

    profile: str  # zero | paper | any file of configs/latency
    delay_s: NonNegative  # s from a frame's exposure until the robot has its result
    jitter_s: NonNegative  # s, std of a half-normal extra delay per frame


@dataclass(frozen=True)
class CameraConfig:
    """The camera (``camera:``): image, rate, mount control, sensor mode, profile, latency."""

    enabled: bool
    width: Pixels
    height: Pixels
    vfov_deg: Annotated[float, Range(gt=0, lt=180)]
    rate_hz: Positive
    near: Positive
    far: Positive
    renderer: Literal["auto", "gl", "egl", "tiny"]
    pan_deg: Degrees
    tilt_deg: Degrees
    control: Literal["none", "pan", "pan_tilt"]
    profile: str  # configs/cameras/<profile>.yaml: lens, sensor, calibration_error
    lens: LensConfig
    sensor: SensorConfig
    calibration_error: CalibrationErrorConfig
    feature_rms_px: Positive  # the detector's feature error the profile is made to give
    mode: Literal["rendered", "fast"]
    fast: FastCameraConfig
    latency: LatencyConfig

    def __post_init__(self) -> None:
        require(self.far > self.near, "far", f"must be > near ({self.near}), got {self.far}")
        corner = math.hypot(self.width, self.height) / self.height  # normalised corner radius
        corner *= math.tan(math.radians(self.vfov_deg) / 2)
        reach = radial_reach(self.lens.distortion)
        require(
            reach > corner,
            "lens.distortion",
            f"{list(self.lens.distortion)} folds the image over: its radial mapping "
            f"r(1 + k1 r^2 + k2 r^4 + k3 r^6) stops growing at distorted radius {reach:.3g}, "
            f"inside the image corner at {corner:.3g} (a lens maps each ray to one pixel)",
        )
        require(
            not any(self.lens.distortion) or invertible(self.lens.distortion, corner),
            "lens.distortion",
            f"{list(self.lens.distortion)} cannot be undone: the undistortion every estimator "
            f"runs (stsf_gym.camera_model.undistort) does not find the rays of the image out to "
            f"its corner at {corner:.3g} (the coefficients are too strong for a real lens)",
        )


@dataclass(frozen=True)
class SonarBeamConfig:
    """The sonar beam model (:mod:`stsf_gym.envs.sensors.sonar_beam`), off by default."""

    enabled: bool
    critical_angle_deg: Annotated[float, Range(gt=0, le=90)]  # incidence at half detection
    angle_width_deg: Annotated[float, Range(gt=0, le=90)]  # how sharply detection falls
    random_prob: Probability  # a reading uniform in [min_range, max_range]
    crosstalk_prob: Probability  # a neighbour's echo (a ring firing all together)


@dataclass(frozen=True)
class SonarConfig:
    """The sonar ring (``sonar:``): transducers, cones, ranges, noise and firing order."""

    count: Count
    beam_width_deg: Annotated[float, Range(gt=0, le=360)]
    rays_per_beam: Count
    height: NonNegative
    min_range: NonNegative
    max_range: Positive
    noise_std: NonNegative
    noise_std_per_m: NonNegative
    dropout_prob: Probability
    firing_order: tuple[int, ...]  # transducers in firing order; empty: all fire at each step end
    firing_interval_s: NonNegative  # s between consecutive firings of the order
    beam: SonarBeamConfig
    cast: Literal["bullet", "plane"] = "plane"  # rays in the ring's plane, or through PyBullet

    def __post_init__(self) -> None:
        require(
            self.max_range > self.min_range,
            "max_range",
            f"must be > min_range ({self.min_range}), got {self.max_range}",
        )
        order = self.firing_order
        require(
            all(0 <= t < self.count for t in order) and len(set(order)) == len(order),
            "firing_order",
            f"must list distinct transducers of 0..{self.count - 1}, got {list(order)}",
        )
        require(
            not order or self.firing_interval_s > 0,
            "firing_interval_s",
            f"must be > 0 with a firing_order, got {self.firing_interval_s}",
        )


@dataclass(frozen=True)
class EncoderConfig:
    """The wheel encoders (``encoders:``): resolution, calibration errors and slip."""

    ticks_per_rev: Count
    radius_error_std: Annotated[float, Range(ge=0, lt=1)]  # relative
    wheelbase_error_std: Annotated[float, Range(ge=0, lt=1)]  # relative
    slip_std: NonNegative


@dataclass(frozen=True)
class RewardConfig:
    """The reward's terms (``reward:``)."""

    progress: float
    goal: float
    collision: float
    time: float
    false_stop: Annotated[float, Range(le=0)] = 0.0  # declare: a stop declared off the goal
    steering_change: Annotated[float, Range(le=0)] = 0.0  # per unit change of action[1]


def check_declare_reward(reward: RewardConfig, time_limit: float) -> None:
    """The reward's optimum is the declared-arrival task (:meth:`PathTask.reward`): time costs
    (``reward.time`` < 0), a goal pays (``reward.goal`` > 0), and a false stop costs at least
    as much as standing until the time limit (``reward.false_stop`` <= ``reward.time`` *
    ``sim.max_episode_seconds``)."""
    require(
        reward.time < 0,
        "reward.time",
        f"must be < 0 under task.protocol: declare (dawdling "
        f"to the time limit must not pay), got {reward.time:g}",
    )
    require(
        reward.goal > 0,
        "reward.goal",
        f"must be > 0 under task.protocol: declare, got {reward.goal:g}",
    )
    waiting = reward.time * time_limit
    require(
        reward.false_stop <= waiting,
        "reward.false_stop",
        f"must be <= reward.time * sim.max_episode_seconds ({waiting:g}: waiting until the time "
        f"limit) under task.protocol: declare, so a false stop never pays better than trying "
        f"on, got {reward.false_stop:g}",
    )


@dataclass(frozen=True)
class TaskConfig:
    """When an episode succeeds (:mod:`stsf_gym.envs.task`): ``reach`` (the paper's protocol) or
    ``declare`` (the agent stops to declare arrival at each goal of the route); and where it
    starts (:mod:`stsf_gym.envs.start_pose`: the world's ``start`` when every ``start_*`` is 0)."""

    protocol: Literal["reach", "declare"]
    goal_radius: Positive  # declare: success radius around each goal at the declared stop (m)
    stop_speed: Positive  # declare: a commanded |forward speed| below this (m/s) ...
    stop_yaw_rate: Positive  # ... and |yaw rate| below this (rad/s) is standing still
    stop_seconds: Positive  # declare: standing still this long declares arrival
    start_along: NonNegative  # m: the start drawn uniformly this far along the path (0: fixed)
    start_lateral: NonNegative  # m: ... and uniformly within +- this across it
    start_yaw_deg: Annotated[float, Range(ge=0, le=180)]  # deg: heading +- this off the path's
    stop_action: bool = False  # declare: a last action entry; above 0 declares arrival at once
    leg_min: NonNegative = 0.0  # m: training legs (envs/start_pose.py): a start on the route ...
    leg_max: NonNegative = 0.0  # ... and one goal this far ahead along it; both 0: the route

    def __post_init__(self) -> None:
        require(
            self.leg_min <= self.leg_max,
            "leg_min",
            f"must not exceed task.leg_max ({self.leg_max:g}), got {self.leg_min:g}",
        )
        require(
            self.leg_max == 0 or self.leg_min >= self.goal_radius,
            "leg_min",
            f"a leg's goal lies ahead of its start: at least task.goal_radius "
            f"({self.goal_radius:g} m), got {self.leg_min:g}",
        )
        require(
            not (self.stop_action or self.leg_max) or self.protocol == "declare",
            "protocol",
            "is 'reach', but task.stop_action and training legs need the declare protocol: "
            "set task.protocol: declare (--set task.protocol=declare, or task__protocol='declare')",
        )


@dataclass(frozen=True)
class RenderConfig:
    """What ``render()`` shows (``render:``): the view and its size."""

    view: Literal["map", "chase", "top"]
    width: Pixels
    height: Pixels


@dataclass(frozen=True)
class EnvConfig:
    """An env's whole configuration: every section of ``configs/default.yaml``, the world."""

    world: WorldConfig
    sim: SimConfig
    robot: RobotConfig
    camera: CameraConfig
    sonar: SonarConfig
    encoders: EncoderConfig
    reward: RewardConfig
    render: RenderConfig
    task: TaskConfig
    faults: tuple[FaultSpec, ...] = ()  # timed faults (envs/fault_spec.py); none by default

    def __post_init__(self) -> None:
        check_clearance(self.world, self.robot.body_radius)
        frame_period = 1 / self.camera.rate_hz
        require(  # a frame is taken at a step's end at most: a slower step would drop frames
            self.sim.control_dt <= frame_period * (1 + 1e-9),
            "sim.control_dt",
            f"must be <= 1/camera.rate_hz ({frame_period:g} s: one frame per step at most), "
            f"got {self.sim.control_dt:g}",
        )
        if self.task.protocol == "declare":
            check_declare_reward(self.reward, self.sim.max_episode_seconds)
        map_ids = sorted(lm.id for lm in self.world.landmarks)
        for i, fault in enumerate(self.faults):
            require(
                fault.start < self.sim.max_episode_seconds,
                f"faults[{i}].start",
                f"must be before the episode ends (sim.max_episode_seconds "
                f"{self.sim.max_episode_seconds:g} s), got {fault.start:g}: it would never act",
            )
            require(
                fault.landmark_id is None or fault.landmark_id in map_ids,
                f"faults[{i}].landmark_id",
                f"must be a landmark of world {self.world.name!r} {map_ids}, "
                f"got {fault.landmark_id}",
            )
            if fault.at is not None:  # a decoy board hangs on a wall of this world, as a map's
                check_board_on_wall(self.world, fault.at, fault.facing_deg, f"faults[{i}]")
        for axis in ("pan", "tilt"):
            limit = getattr(self.robot, f"{axis}_limit_deg")
            value = getattr(self.camera, f"{axis}_deg")
            require(
                abs(value) <= limit,
                f"camera.{axis}_deg",
                f"must be within robot.{axis}_limit_deg (±{limit:g}), got {value}",
            )


#: The env config's sections (the keyword arguments an env takes besides its own).
SECTIONS = tuple(f.name for f in fields(EnvConfig) if f.name != "world")


def load_config(
    config: str | Path | Mapping | None = None,
    *,
    world: str | Mapping | None = None,
    **overrides: Any,
) -> EnvConfig:
    """Build the env config from layers: defaults <- ``world`` <- ``config`` <- ``overrides``.

    ``config`` is a YAML path or a mapping of sections; ``world`` a world name, YAML path or
    mapping; ``overrides`` flat keys such as ``camera__width=640`` or whole sections
    (``camera={"width": 640}``). A world given by name or path replaces the current one; a
    world given as a mapping is merged into it. Errors name the file that set the bad key.
    """
    default = CONFIG_DIR / "default.yaml"
    user = (shown(config), read_yaml(config)) if isinstance(config, str | Path) else (None, config)
    layers = [(shown(default), read_yaml(default)), (None, {"world": world}), user]
    layers.append((None, overrides_to_tree(overrides)))
    tree: dict = {}
    sources = KeySources()
    for source, layer in layers:
        layer = dict(layer or {})
        layer_world = layer.pop("world", None)
        tree = deep_merge(tree, layer)
        sources.record(layer, source)
        if isinstance(layer_world, str | Path):
            tree["world"] = {}
            sources.forget("world")
            for file, data in world_files(layer_world):
                tree["world"] = deep_merge(tree["world"], data)
                sources.record({"world": data}, shown(file))  # an empty file is named too
        elif isinstance(layer_world, Mapping):
            tree["world"] = deep_merge(tree.get("world", {}), layer_world)
            sources.record(layer_world, source, "world")
        elif layer_world is not None:
            raise ConfigError(
                f"world must be a name, a YAML path or a mapping, got {layer_world!r}",
                "world",
                source,
            )
    for name in SECTIONS:  # a section given a value (``camera="fast"``) is not merged into
        if name != "faults" and not isinstance(tree.get(name, {}), Mapping):  # faults: a list
            message = f"{name} is a section: it must be a mapping of its keys, got {tree[name]!r}"
            raise ConfigError(message, name, sources.file_of(name) or None)
    _add_camera_profile(tree, sources)
    try:
        return build(EnvConfig, tree, "")
    except ConfigError as err:
        raise sources.attribute(err) from err


def check_env_keywords(owner: str, overrides: Mapping[str, Any], named: tuple[str, ...]) -> None:
    """Raise :class:`~stsf_gym.validation.UnexpectedKeyword` (a ``TypeError`` and a
    :class:`ConfigError`) for a keyword argument of env ``owner`` (whose own parameters are
    ``named``) that names no config section."""
    check_keywords(owner, overrides, [*named, *SECTIONS])


def _add_camera_profile(tree: dict, sources: KeySources) -> None:
    """Fill the camera section from its profile file, and its latency section from its own
    profile; keys a layer set stay as set."""
    camera = tree.setdefault("camera", {})
    tree["camera"] = _with_profile(camera, "cameras", "camera", sources)
    latency = tree["camera"].setdefault("latency", {})
    tree["camera"]["latency"] = _with_profile(latency, "latency", "camera.latency", sources)


def _with_profile(section: dict, folder: str, label: str, sources: KeySources) -> dict:
    """``section`` over the keys of ``configs/<folder>/<section['profile']>.yaml``."""
    name = section.get("profile")
    known = sorted(p.stem for p in (CONFIG_DIR / folder).glob("*.yaml"))
    file = CONFIG_DIR / folder / f"{name}.yaml"
    if not isinstance(name, str) or not file.is_file():
        raise ConfigError(
            f"{label}.profile must be one of {known}, got {name!r}",
            f"{label}.profile",
            sources.file_of(f"{label}.profile") or None,
        )
    profile = read_yaml(file)
    sources.record(profile, shown(file), label, keep=True)
    return deep_merge(profile, section)
