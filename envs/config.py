"""World and sensor configuration: typed sections loaded from YAML, unknown keys rejected.

Every number lives in ``configs/``: ``configs/default.yaml`` holds the robot, sensors and task,
``configs/worlds/<name>.yaml`` the worlds. :func:`load_config` merges, in order, the defaults,
a user config (YAML path or dict), then keyword overrides, and builds an :class:`EnvConfig`.
A misspelt or unknown key raises :class:`ConfigError` naming the full key path.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import yaml

from stsf_gym.vision.landmarks import LandmarkPattern

CONFIG_DIR = Path(__file__).resolve().parent.parent / "configs"


class ConfigError(ValueError):
    """A configuration key or value is invalid; the message names it."""


@dataclass(frozen=True)
class LandmarkSpec:
    id: int
    at: tuple[float, float]  # a point on the wall centre line the landmark hangs on (m)
    facing_deg: float  # world yaw of the landmark's outward normal


@dataclass(frozen=True)
class ObstacleSpec:
    shape: Literal["box", "cylinder"]
    position: tuple[float, float]
    size: tuple[float, ...]  # box: (length, width, height) / cylinder: (radius, height)
    yaw_deg: float = 0.0


@dataclass(frozen=True)
class WorldConfig:
    name: str
    walls: tuple[tuple[float, float, float, float], ...]  # centre-line segments x1, y1, x2, y2
    wall_height: float
    wall_thickness: float
    path: tuple[tuple[float, float], ...]
    start: tuple[float, float, float]
    goal_radius: float
    landmark_height: float
    landmark_pattern: LandmarkPattern
    landmarks: tuple[LandmarkSpec, ...]
    obstacles: tuple[ObstacleSpec, ...] = ()

    @property
    def goal(self) -> tuple[float, float]:
        return self.path[-1]


@dataclass(frozen=True)
class SimConfig:
    physics_hz: float
    control_dt: float
    max_episode_seconds: float


@dataclass(frozen=True)
class RobotConfig:
    wheel_radius: float
    wheelbase: float
    body_radius: float
    body_height: float
    mass: float
    wheel_friction: float
    wheel_max_torque: float
    max_speed: float
    max_yaw_rate: float
    nominal_speed: float
    camera_height: float
    camera_forward: float
    pan_limit_deg: float
    tilt_limit_deg: float


@dataclass(frozen=True)
class FastCameraConfig:
    """Statistics of the detector, fitted on rendered frames (``benchmarks/fast_sensor_fit.py``)."""

    feature_noise_px: float  # std of each square centre's pixel error, per axis
    detect_size_px: float  # square pitch (px) at which half of the boards are detected
    detect_size_scale: float  # logistic width of the detection rate in square pitch (px)
    false_detection_rate: float  # wrong-id detections per frame
    max_detections: int  # detection slots in the observation


@dataclass(frozen=True)
class CameraConfig:
    enabled: bool
    width: int
    height: int
    vfov_deg: float
    rate_hz: float
    near: float
    far: float
    renderer: Literal["auto", "egl", "tiny"]
    pan_deg: float
    tilt_deg: float
    control: Literal["none", "pan", "pan_tilt"]
    noise_std: float
    mode: Literal["rendered", "fast"]
    fast: FastCameraConfig


@dataclass(frozen=True)
class SonarConfig:
    count: int
    beam_width_deg: float
    rays_per_beam: int
    height: float
    min_range: float
    max_range: float
    noise_std: float
    noise_std_per_m: float
    dropout_prob: float


@dataclass(frozen=True)
class EncoderConfig:
    ticks_per_rev: int
    radius_error_std: float
    wheelbase_error_std: float
    slip_std: float


@dataclass(frozen=True)
class RewardConfig:
    progress: float
    goal: float
    collision: float
    time: float


@dataclass(frozen=True)
class RenderConfig:
    view: Literal["chase", "top"]
    width: int
    height: int


@dataclass(frozen=True)
class EnvConfig:
    world: WorldConfig
    sim: SimConfig
    robot: RobotConfig
    camera: CameraConfig
    sonar: SonarConfig
    encoders: EncoderConfig
    reward: RewardConfig
    render: RenderConfig


def read_yaml(path: str | Path) -> dict:
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"config file not found: {path}")
    data = yaml.safe_load(path.read_text()) or {}
    if not isinstance(data, dict):
        raise ConfigError(f"config file {path} must hold a mapping, got {type(data).__name__}")
    return data


def deep_merge(base: dict, update: Mapping) -> dict:
    """Return ``base`` updated by ``update``; nested mappings merge, anything else replaces."""
    merged = copy.deepcopy(base)
    for key, value in update.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), dict):
            merged[key] = deep_merge(merged[key], value)
        else:
            merged[key] = copy.deepcopy(value)
    return merged


def overrides_to_tree(overrides: Mapping[str, Any]) -> dict:
    """Turn flat overrides (``camera__width=640`` or ``"camera.width": 640``) into a tree."""
    tree: dict = {}
    for key, value in overrides.items():
        *parents, leaf = key.replace("__", ".").split(".")
        node = tree
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    return tree


def resolve_world(world: str | Path) -> dict:
    """A world by name (``configs/worlds/<name>.yaml``) or by YAML path.

    A world file may name another in ``extends``; its keys are merged over that one.
    """
    candidate = Path(world)
    if candidate.suffix not in (".yaml", ".yml"):
        candidate = CONFIG_DIR / "worlds" / f"{world}.yaml"
        if not candidate.is_file():
            known = sorted(p.stem for p in (CONFIG_DIR / "worlds").glob("*.yaml"))
            raise ConfigError(f"unknown world {str(world)!r}; known worlds: {', '.join(known)}")
    data = read_yaml(candidate)
    base = data.pop("extends", None)
    return deep_merge(resolve_world(base), data) if base else data


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
    world given as a mapping is merged into it.
    """
    if isinstance(config, str | Path):
        config = read_yaml(config)
    layers = [read_yaml(CONFIG_DIR / "default.yaml"), {"world": world}, config or {}]
    layers.append(overrides_to_tree(overrides))
    tree: dict = {}
    for layer in layers:
        layer = dict(layer)
        layer_world = layer.pop("world", None)
        tree = deep_merge(tree, layer)
        if isinstance(layer_world, str | Path):
            tree["world"] = resolve_world(layer_world)
        elif isinstance(layer_world, Mapping):
            tree["world"] = deep_merge(tree.get("world", {}), layer_world)
        elif layer_world is not None:
            raise ConfigError(
                f"world must be a name, a YAML path or a mapping, got {layer_world!r}"
            )
    return build(EnvConfig, tree, "")


def build(cls: type, data: Any, path: str) -> Any:
    """Construct dataclass ``cls`` from nested ``data``, naming any bad key by its path."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"{path or 'config'} must be a mapping, got {data!r}")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = [k for k in data if k not in fields]
    if unknown:
        key = unknown[0]
        hint = difflib.get_close_matches(str(key), fields, n=1)
        suggestion = f" (did you mean {_join(path, hint[0])!r}?)" if hint else ""
        raise ConfigError(f"unknown config key {_join(path, key)!r}{suggestion}")
    values = {}
    for name, f in fields.items():
        if name in data:
            values[name] = _coerce(hints[name], data[name], _join(path, name))
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ConfigError(f"missing config key {_join(path, name)!r}")
    try:
        return cls(**values)
    except (TypeError, ValueError) as err:
        raise ConfigError(f"invalid {path or 'config'}: {err}") from err


def _coerce(hint: Any, value: Any, path: str) -> Any:
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if dataclasses.is_dataclass(hint):
        return build(hint, value, path)
    if origin is Literal:
        if value not in args:
            raise ConfigError(f"{path} must be one of {list(args)}, got {value!r}")
        return value
    if origin is tuple:
        if not isinstance(value, list | tuple):
            raise ConfigError(f"{path} must be a list, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_coerce(args[0], v, f"{path}[{i}]") for i, v in enumerate(value))
        if len(value) != len(args):
            raise ConfigError(f"{path} must have {len(args)} entries, got {len(value)}")
        return tuple(
            _coerce(a, v, f"{path}[{i}]") for i, (a, v) in enumerate(zip(args, value, strict=True))
        )
    if origin in (typing.Union, types.UnionType):
        return value
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{path} must be true or false, got {value!r}")
        return value
    if hint in (int, float):
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(f"{path} must be a number, got {value!r}")
        if hint is int and value != int(value):
            raise ConfigError(f"{path} must be an integer, got {value!r}")
        return hint(value)
    if hint is str and not isinstance(value, str):
        raise ConfigError(f"{path} must be a string, got {value!r}")
    return value


def _join(path: str, key: Any) -> str:
    return f"{path}.{key}" if path else str(key)
