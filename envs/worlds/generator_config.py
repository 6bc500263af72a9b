"""Settings of the world generator: ranges read from ``configs/generator/*.yaml``, validated.

Every ``[low, high]`` pair must have ``low <= high``; the splits must be disjoint. Errors
name the file and the key, as for env configs (:mod:`stsf_gym.validation`).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

from stsf_gym.config_files import CONFIG_DIR, deep_merge, read_yaml, shown
from stsf_gym.validation import ConfigError, Count, NonNegative, Positive, Range, build, require
from stsf_gym.vision.landmarks import LandmarkPattern

DEFAULT_GENERATOR = CONFIG_DIR / "generator" / "default.yaml"
SPLITS = ("train", "val", "test")  # val: model selection while training, never benchmarked


def _ordered(pair: tuple, field: str) -> None:
    require(pair[0] <= pair[1], field, f"must be [low, high] with low <= high, got {list(pair)}")


@dataclass(frozen=True)
class VisibilityConfig:
    """When a board counts as seen from a path sample (``visibility:`` of the generator)."""

    min_range: Positive
    max_range: Positive
    max_view_deg: Annotated[float, Range(gt=0, lt=90)]
    min_board_px: Positive
    sample_step: Positive
    landmarks_in_view: Count
    candidate_step: Positive
    #: the density dial: share of path points that see a board, [low, high]; 1: every one
    coverage: tuple[Annotated[float, Range(gt=0, le=1)], Annotated[float, Range(gt=0, le=1)]] = (
        1.0,
        1.0,
    )
    dark_stretch: tuple[Positive, Positive] = (10.0, 20.0)  # m of path with no board in view

    def __post_init__(self) -> None:
        _ordered((self.min_range, self.max_range), "max_range")
        _ordered(self.coverage, "coverage")
        _ordered(self.dark_stretch, "dark_stretch")

    @property
    def sparse(self) -> bool:
        """Dark stretches are planned (coverage below 1)."""
        return self.coverage[0] < 1.0


@dataclass(frozen=True)
class ClutterConfig:
    """The clutter the generator places (``clutter:``)."""

    count: tuple[Annotated[int, Range(ge=0)], Annotated[int, Range(ge=0)]]
    size: tuple[Positive, Positive]
    height: tuple[Positive, Positive]
    path_clearance: NonNegative
    corner_distance: NonNegative

    def __post_init__(self) -> None:
        for name in ("count", "size", "height"):
            _ordered(getattr(self, name), name)


@dataclass(frozen=True)
class FixedWorldConfig:
    """What every generated world shares (``world:`` of the generator): walls, goal, boards."""

    wall_height: Positive
    wall_thickness: Positive
    goal_radius: Positive
    landmark_height: NonNegative
    landmark_pattern: LandmarkPattern


@dataclass(frozen=True)
class GeneratorConfig:
    """The world generator's ranges (``configs/generator/default.yaml``), typed and checked."""

    segments: tuple[Count, Count]
    segment_length: tuple[Positive, Positive]
    width: tuple[Positive, Positive]
    min_path_length: Positive
    branches: tuple[Annotated[int, Range(ge=0)], Annotated[int, Range(ge=0)]]
    branch_length: tuple[Positive, Positive]
    end_margin: Positive
    min_gap: Positive
    grid: Positive
    attempts: Count
    visibility: VisibilityConfig
    clutter: ClutterConfig
    world: FixedWorldConfig
    splits: dict
    goal_overrun: tuple[Positive, Positive] | None = (
        None  # corridor past the goal; None: end_margin
    )
    halls: tuple[Annotated[int, Range(ge=0)], Annotated[int, Range(ge=0)]] = (0, 0)
    hall_width: tuple[Positive, Positive] = (11.0, 14.0)  # open halls: wider than 2 sonar ranges
    junction_arms: tuple[Annotated[int, Range(ge=0)], Annotated[int, Range(ge=0, le=2)]] = (0, 0)
    arm_length: tuple[Positive, Positive] = (3.0, 6.0)  # look-alike corridors at a turn
    route_goals: tuple[Annotated[int, Range(ge=0)], Annotated[int, Range(ge=0)]] = (0, 0)
    route_spacing: Positive = 3.0  # m along the path between goals, and from the start

    def __post_init__(self) -> None:
        names = ("segments", "segment_length", "width", "branches", "branch_length", "halls")
        names += ("hall_width", "junction_arms", "arm_length", "route_goals")
        for name in names:
            _ordered(getattr(self, name), name)
        longest = self.segments[1] * self.segment_length[1]
        require(
            self.min_path_length <= longest,
            "min_path_length",
            f"can never be reached: at most segments[1] x segment_length[1] = {longest:g} m, "
            f"got {self.min_path_length:g}",
        )
        if self.goal_overrun is not None:
            _ordered(self.goal_overrun, "goal_overrun")
        require(
            isinstance(self.splits, Mapping) and sorted(self.splits) == sorted(SPLITS),
            "splits",
            f"must name exactly {list(SPLITS)}, got {self.splits!r}",
        )
        for name, value in self.splits.items():
            ok = isinstance(value, list | tuple) and len(value) == 2
            ok = ok and all(isinstance(v, int) and not isinstance(v, bool) for v in value)
            require(
                ok and value[0] >= 0 and value[1] >= 1,
                f"splits.{name}",
                f"must be [first world seed >= 0, count >= 1], got {value!r}",
            )
        ranges = {name: range(v[0], v[0] + v[1]) for name, v in self.splits.items()}
        for a, b in itertools.combinations(SPLITS, 2):
            first, second = ranges[a], ranges[b]
            require(
                first.stop <= second.start or second.stop <= first.start,
                "splits",
                f"{a} [{first.start}, {first.stop - 1}] and {b} [{second.start}, "
                f"{second.stop - 1}] world seeds must not overlap",
            )

    def split_range(self, split: str) -> range:
        """World seeds of ``split`` (``"train"``, ``"val"`` or ``"test"``)."""
        if split not in SPLITS:
            raise ConfigError(f"split must be one of {list(SPLITS)}, got {split!r}")
        first, count = self.splits[split]
        return range(first, first + count)


def load_generator_config(
    generator: str | Path | Mapping | None = None, **overrides
) -> GeneratorConfig:
    """``configs/generator/default.yaml`` merged with ``generator`` (a YAML path, or a mapping)
    and keyword overrides of whole keys; errors name the file and the key."""
    base = read_yaml(DEFAULT_GENERATOR)
    source = shown(DEFAULT_GENERATOR)
    if isinstance(generator, str | Path):
        base, source = deep_merge(base, read_yaml(generator)), shown(generator)
    elif isinstance(generator, Mapping):
        base, source = deep_merge(base, generator), None
    elif generator is not None:
        raise ConfigError(f"generator must be a YAML path or a mapping, got {generator!r}")
    try:
        return build(GeneratorConfig, deep_merge(base, overrides), "generator")
    except ConfigError as err:
        raise ConfigError(err.message, err.key, source) from err
