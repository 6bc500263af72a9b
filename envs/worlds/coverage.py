"""The density dial's measure: how much of a world's path sees a landmark.

A path sample (every ``visibility.sample_step`` m, :func:`~stsf_gym.envs.worlds.visibility.
path_samples`) is **lit** when it sees at least one of the world's boards by the generator's
definition of *seen* (:mod:`stsf_gym.envs.worlds.visibility`: range, viewing angle, pan, sight
line, in frame, at least ``min_board_px``), and **dark** otherwise. The coverage is the share
of lit samples; the longest dark stretch is the longest run of dark samples along the path.
A real building ranges from a corridor with a sign every few metres (coverage 1) to halls and
service corridors with 10-20 m between signs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stsf_gym.envs.worlds.generator_config import GeneratorConfig
from stsf_gym.envs.worlds.visibility import (
    CameraView,
    path_samples,
    sample_arc_lengths,
    seen_matrix,
)

BOARD_OFF_WALL = 0.02  # m between the wall face and the board (as corridor.py builds it)


@dataclass(frozen=True)
class Coverage:
    """How much of a world's path sees a board: share of samples, longest dark stretch."""

    fraction: float  # share of path samples that see a board
    longest_dark_m: float  # longest stretch of path from which no board is seen


def board_centres(at: np.ndarray, normals: np.ndarray, thickness: float) -> np.ndarray:
    """Board centres (N, 2) of boards hung at wall points ``at`` facing ``normals``."""
    return np.asarray(at, float) + (thickness / 2 + BOARD_OFF_WALL) * np.asarray(normals, float)


def coverage_of(lit: np.ndarray, arcs: np.ndarray) -> Coverage:
    """The coverage of per-sample ``lit`` flags at arc lengths ``arcs``."""
    longest, start = 0.0, None
    for k, is_lit in enumerate(np.append(lit, True)):
        if not is_lit and start is None:
            start = k
        elif is_lit and start is not None:
            end = arcs[min(k, len(arcs) - 1)]
            longest = max(longest, float(end - arcs[max(start - 1, 0)]))
            start = None
    return Coverage(float(np.mean(lit)), longest)


def landmark_coverage(world, gen: GeneratorConfig, env) -> Coverage:
    """The measured coverage of ``world`` (a WorldConfig) for the camera of ``env`` (an
    EnvConfig) under the generator's visibility limits."""
    path = np.asarray(world.path, float)
    samples, headings = path_samples(path, gen.visibility.sample_step)
    arcs = sample_arc_lengths(path, gen.visibility.sample_step)
    if not world.landmarks:
        return coverage_of(np.zeros(len(samples), bool), arcs)
    angles = np.radians([lm.facing_deg for lm in world.landmarks])
    normals = np.column_stack([np.cos(angles), np.sin(angles)])
    centres = board_centres([lm.at for lm in world.landmarks], normals, world.wall_thickness)
    circles = np.array(
        [(*o.position, _radius(o.shape, o.size)) for o in world.obstacles], dtype=float
    ).reshape(-1, 3)
    seen = seen_matrix(
        samples,
        headings,
        centres,
        normals,
        np.asarray(world.walls, float),
        circles,
        world.wall_thickness,
        world.landmark_pattern.size,
        world.landmark_height,
        CameraView.from_env_config(env),
        gen.visibility,
    )
    return coverage_of(seen.any(axis=1), arcs)


def _radius(shape: str, size) -> float:
    """Bounding-circle radius of an obstacle footprint."""
    return size[0] if shape == "cylinder" else math.hypot(size[0], size[1]) / 2
