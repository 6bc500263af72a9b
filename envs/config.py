"""World and sensor configuration: typed sections loaded from YAML, unknown keys rejected.

Every number lives in ``configs/``: ``configs/default.yaml`` holds the robot, sensors and task,
``configs/worlds/<name>.yaml`` the worlds. :func:`load_config` merges, in order, the defaults,
a user config (YAML path or dict), then keyword overrides, and builds an :class:`EnvConfig`.
Every number has an allowed range (``Annotated[..., Range(...)]``, :mod:`stsf_gym.validation`) and
the world's geometry is checked (:mod:`stsf_gym.envs.worlds.spec`). The world's schema and the
sensors' sections live by their code (:mod:`~stsf_gym.envs.worlds.spec`,
:mod:`~stsf_gym.envs.sensors.settings`) and are re-exported here. A misspelt or unknown key, a
value of the wrong type or out of range raises :class:`ConfigError` naming the YAML file that set
it, the full key path and what is allowed: ``configs/x.yaml: robot.wheel_radius must be in
(0, 10], got -0.1``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Annotated, Any, Literal

from stsf_gym.config_files import (
    CONFIG_DIR,
    deep_merge,
    overrides_to_tree,
    read_yaml,
    shown,
    world_files,
)
from stsf_gym.envs.fault_spec import FaultSpec
from stsf_gym.envs.sensors.settings import (
    CalibrationErrorConfig,
    CameraConfig,
    EncoderConfig,
    FastCameraConfig,
    LatencyConfig,
    LensConfig,
    SensorConfig,
    SonarBeamConfig,
    SonarConfig,
)
from stsf_gym.envs.worlds.spec import (
    LandmarkSpec,
    ObstacleSpec,
    WorldConfig,
    check_board_on_wall,
    check_clearance,
)
from stsf_gym.validation import (
    ROBOT_EXTENT_M,
    ConfigError,
    KeySources,
    NonNegative,
    Pixels,
    Positive,
    Range,
    RobotLength,
    build,
    check_keywords,
    require,
)

__all__ = [  # re-exported: the config API lives here
    "CONFIG_DIR",
    "CalibrationErrorConfig",
    "CameraConfig",
    "EncoderConfig",
    "EnvConfig",
    "FastCameraConfig",
    "LandmarkSpec",
    "LatencyConfig",
    "LensConfig",
    "ObstacleSpec",
    "SensorConfig",
    "SonarBeamConfig",
    "SonarConfig",
    "WorldConfig",
    "build",
    "load_config",
    "overrides_to_tree",
    "read_yaml",
]


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
class RewardConfig:
    """The reward's terms (``reward:``)."""

    progress: float
    goal: float
    collision: float
    time: float
    false_stop: Annotated[float, Range(le=0)] = 0.0  # declare: a stop declared off the goal
    steering_change: Annotated[float, Range(le=0)] = 0.0  # per unit change of action[1]


def check_declare_reward(reward: RewardConfig, time_limit: float, false_stop_ends: bool) -> None:
    """The reward's optimum is the declared-arrival task (:meth:`PathTask.reward`): time costs
    (``reward.time`` < 0), a goal pays (``reward.goal`` > 0), and a false stop that ends the
    episode costs at least as much as standing until the time limit (``reward.false_stop`` <=
    ``reward.time`` * ``sim.max_episode_seconds``); one that lets the leg go on (the
    training-only ``task.false_stop_ends: false``) costs something (< 0), so no declaration
    off the goal pays better than none."""
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
    if not false_stop_ends:
        require(
            reward.false_stop < 0,
            "reward.false_stop",
            "must be < 0 under task.false_stop_ends: false, so a declaration off the goal "
            f"never pays better than none, got {reward.false_stop:g}",
        )
        return
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
    false_stop_ends: bool = True  # declare: False (training only) lets a leg go on after one

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
            not (self.stop_action or self.leg_max or not self.false_stop_ends)
            or self.protocol == "declare",
            "protocol",
            "is 'reach', but task.stop_action, training legs and task.false_stop_ends need "
            "the declare protocol: "
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
            check_declare_reward(
                self.reward, self.sim.max_episode_seconds, self.task.false_stop_ends
            )
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
