"""Typed, range-checked configs: frozen dataclasses built from nested mappings (YAML).

A field's type is its schema. ``Annotated[float, Range(gt=0)]`` adds an allowed range, and a
dataclass may check relations between its fields in ``__post_init__`` with :func:`require`.
:func:`build` constructs a dataclass from a mapping and raises :class:`ConfigError` naming the
full key path, the allowed values and the value given, e.g.
``robot.wheel_radius must be in (0, 10], got -0.1``.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import re
import types
import typing
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Annotated, Any, Literal


class ConfigError(ValueError):
    """A configuration key or value is invalid; the message names the key (and its file).

    ``key`` is the full key path (``camera.width``) when one key is to blame, and ``source``
    the file that set it, when known.
    """

    def __init__(self, message: str, key: str | None = None, source: str | None = None) -> None:
        super().__init__(f"{source}: {message}" if source else message)
        self.message, self.key, self.source = message, key, source


class UnexpectedKeyword(ConfigError, TypeError):
    """A keyword argument no constructor of this kind takes: a ``TypeError`` saying
    ``unexpected keyword argument 'NAME'``, as Python and Gymnasium envs raise (clients such as
    TorchRL's ``GymEnv`` retry without a keyword on exactly that), and a :class:`ConfigError`.
    Built as a ConfigError is (``gym.make`` raises it again with its own message added)."""


def did_you_mean(name: str, known: Iterable) -> str:
    """`` (did you mean 'x'?)`` for the name of ``known`` closest to a mistyped ``name``, or
    nothing when none is close."""
    close = difflib.get_close_matches(str(name), [str(k) for k in known], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def check_keywords(owner: str, keywords: Mapping[str, Any], known: list[str]) -> None:
    """Raise :class:`UnexpectedKeyword` for the first of ``keywords`` (flat ``camera__width``
    or dotted keys count by their first part) that is not in ``known``."""
    for key in keywords:
        name = str(key).replace("__", ".").partition(".")[0]
        if name not in known:
            hint = difflib.get_close_matches(name, known, n=1)
            suggestion = f" (did you mean {hint[0]!r}?)" if hint else ""
            message = f"{owner}() got an unexpected keyword argument {name!r}{suggestion}"
            raise UnexpectedKeyword(f"{message}; it takes {', '.join(known)}", name)


def reset_options(options: Any) -> dict:
    """A copy of ``reset(options=...)``: a mapping or None, anything else refused by name."""
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise ValueError(f"reset options must be a mapping (dict) or None, got {options!r}")
    return dict(options)


class FieldError(ValueError):
    """Raised in a config dataclass's ``__post_init__``: ``field`` (relative key) is invalid."""

    def __init__(self, field: str, problem: str) -> None:
        super().__init__(f"{field} {problem}")
        self.field, self.problem = field, problem


def require(condition: bool, field: str, problem: str) -> None:
    """Raise :class:`FieldError` for ``field`` unless ``condition`` holds."""
    if not condition:
        raise FieldError(field, problem)


@dataclass(frozen=True)
class Range:
    """Allowed values of a number: any of the bounds ``gt``, ``ge``, ``lt``, ``le``."""

    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None

    def __contains__(self, value: float) -> bool:
        return not (
            (self.gt is not None and value <= self.gt)
            or (self.ge is not None and value < self.ge)
            or (self.lt is not None and value >= self.lt)
            or (self.le is not None and value > self.le)
        )

    def __str__(self) -> str:
        low, high = _first(self.gt, self.ge), _first(self.lt, self.le)
        if low is not None and high is not None:
            left, right = "(" if self.gt is not None else "[", ")" if self.lt is not None else "]"
            return f"in {left}{low:g}, {high:g}{right}"
        if low is not None:
            return f"{'>' if self.gt is not None else '>='} {low:g}"
        if high is not None:
            return f"{'<' if self.lt is not None else '<='} {high:g}"
        return "any number"


def _first(*values: float | None) -> float | None:
    return next((v for v in values if v is not None), None)


#: No setting of this project comes near this magnitude (world seeds stop at 2e6); a number beyond
#: it is refused wherever it enters, before its square or product overflows float32 (PyBullet).
MAGNITUDE_LIMIT = 1e9
#: m: how far from the origin a world reaches. PyBullet stores positions as float32, whose
#: resolution at 10 km is about a millimetre: farther, contacts and rays lose their geometry.
WORLD_EXTENT_M = 1e4
#: m: the largest part of a mobile robot (wheel radius, wheelbase, body, camera mount).
ROBOT_EXTENT_M = 10.0

Positive = Annotated[float, Range(gt=0)]
NonNegative = Annotated[float, Range(ge=0)]
Probability = Annotated[float, Range(ge=0, le=1)]
Count = Annotated[int, Range(ge=1)]
Pixels = Annotated[int, Range(ge=1, le=8192)]
Degrees = Annotated[float, Range(ge=-360, le=360)]
#: A world coordinate (m).
Coordinate = Annotated[float, Range(ge=-WORLD_EXTENT_M, le=WORLD_EXTENT_M)]
#: A length in a world: a wall's height or thickness, an obstacle's size, a radius (m).
WorldLength = Annotated[float, Range(gt=0, le=WORLD_EXTENT_M)]
#: A length of the robot: a wheel radius, the wheelbase, the body, the camera mount (m).
RobotLength = Annotated[float, Range(gt=0, le=ROBOT_EXTENT_M)]


def build(cls: type, data: Any, path: str) -> Any:
    """Construct dataclass ``cls`` from nested ``data``, naming any bad key by its path."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"{path or 'config'} must be a mapping, got {data!r}", path)
    hints = typing.get_type_hints(cls, include_extras=True)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = [k for k in data if k not in fields]
    if unknown:
        key = _join(path, unknown[0])
        hint = difflib.get_close_matches(str(unknown[0]), fields, n=1)
        suggestion = f" (did you mean {_join(path, hint[0])!r}?)" if hint else ""
        raise ConfigError(f"unknown config key {key!r}{suggestion}", key)
    values = {}
    for name, f in fields.items():
        if name in data:
            values[name] = _coerce(hints[name], data[name], _join(path, name))
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ConfigError(f"missing config key {_join(path, name)!r}", _join(path, name))
    try:
        return cls(**values)
    except FieldError as err:
        key = _join(path, err.field)
        raise ConfigError(f"{key} {err.problem}", key) from err
    except (TypeError, ValueError) as err:
        raise ConfigError(f"invalid {path or 'config'}: {err}", path) from err


def _coerce(hint: Any, value: Any, path: str) -> Any:
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is Annotated:
        ranges = [m for m in hint.__metadata__ if isinstance(m, Range)]
        if args[0] in (int, float):
            return check_number(value, path, *ranges, integer=args[0] is int)
        value = _coerce(args[0], value, path)
        for allowed in ranges:
            _check_range(value, allowed, path)
        return value
    if dataclasses.is_dataclass(hint):
        return build(hint, value, path)
    if origin is Literal:
        if value not in args:
            raise ConfigError(f"{path} must be one of {list(args)}, got {value!r}", path)
        return value
    if origin is tuple:
        return _coerce_tuple(args, value, path)
    if origin in (typing.Union, types.UnionType):
        return _coerce_union(args, value, path)
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{path} must be true or false, got {value!r}", path)
        return value
    if hint in (int, float):
        return check_number(value, path, integer=hint is int)
    if hint is str and not isinstance(value, str):
        raise ConfigError(f"{path} must be a string, got {value!r}", path)
    return value


def _coerce_union(args: tuple, value: Any, path: str) -> Any:
    """``value`` as the first member of the union that takes it (``None`` for ``X | None``)."""
    if value is None and type(None) in args:
        return None
    problems = []
    for member in (a for a in args if a is not type(None)):
        try:
            return _coerce(member, value, path)
        except ConfigError as err:
            problems.append(err.message.removeprefix(f"{path} "))
    raise ConfigError(f"{path} {' or '.join(problems)}", path)


def _coerce_tuple(args: tuple, value: Any, path: str) -> tuple:
    if not isinstance(value, list | tuple):
        raise ConfigError(f"{path} must be a list, got {value!r}", path)
    if len(args) == 2 and args[1] is Ellipsis:
        return tuple(_coerce(args[0], v, f"{path}[{i}]") for i, v in enumerate(value))
    if len(value) != len(args):
        raise ConfigError(f"{path} must have {len(args)} entries, got {len(value)}", path)
    return tuple(
        _coerce(a, v, f"{path}[{i}]") for i, (a, v) in enumerate(zip(args, value, strict=True))
    )


def check_number(value: Any, path: str, *allowed: Range, integer: bool = False) -> float | int:
    """``value`` as a finite number (``int`` with ``integer``) within each ``allowed`` range and
    :data:`MAGNITUDE_LIMIT`, or a :class:`ConfigError` naming ``path``: the check every number
    of a config passes, and numbers that enter elsewhere (hyper-parameters, options)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(f"{path} must be a number, got {value!r}", path)
    if not math.isfinite(value):
        raise ConfigError(f"{path} must be a finite number, got {value!r}", path)
    if integer and value != int(value):
        raise ConfigError(f"{path} must be an integer, got {value!r}", path)
    number = int(value) if integer else float(value)
    for each in allowed:
        _check_range(number, each, path)
    if abs(number) > MAGNITUDE_LIMIT:
        raise ConfigError(f"{path} must be within ±{MAGNITUDE_LIMIT:g}, got {number!r}", path)
    return number


def _check_range(value: float, allowed: Range, path: str) -> None:
    if value not in allowed:
        raise ConfigError(f"{path} must be {allowed}, got {value!r}", path)


def _join(path: str, key: Any) -> str:
    return f"{path}.{key}" if path else str(key)


class KeySources:
    """Which file set each key of a config merged from layers, to name that file in errors."""

    def __init__(self) -> None:
        self._files: dict[str, str] = {}  # key path -> file ("" when set by a mapping)

    def record(self, tree: Mapping, file: str | None, prefix: str = "", keep: bool = False) -> None:
        """Note ``file`` (``None``: not from a file) as the source of every key in ``tree``;
        with ``keep``, only of keys no layer has set (``tree`` holds defaults)."""
        for key, value in tree.items():
            path = _join(prefix, key)
            if not (keep and path in self._files):
                self._files[path] = file or ""
            if isinstance(value, Mapping):
                self.record(value, file, path, keep)

    def forget(self, prefix: str) -> None:
        """Drop ``prefix`` and the keys under it (a section replaced as a whole)."""
        for key in [k for k in self._files if k == prefix or k.startswith(f"{prefix}.")]:
            del self._files[key]

    def file_of(self, key: str | None) -> str:
        """The file that set ``key`` or its nearest enclosing key ("" if none)."""
        while key:
            if key in self._files:
                return self._files[key]
            parent = re.sub(r"(\.[^.\[]+|\[\d+\])$", "", key)
            key = parent if parent != key else None
        return ""

    def attribute(self, err: ConfigError) -> ConfigError:
        """``err`` with the file that set its key, when known."""
        file = self.file_of(err.key)
        return ConfigError(err.message, err.key, file) if file and not err.source else err
