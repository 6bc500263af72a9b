"""Which landmarks the robot's camera sees from points of its path: the generator's guarantee.

**Definition.** The path is sampled every ``sample_step`` metres from start to goal (both
included, and every turn twice: once with the heading before it, once after); the robot
stands on the sample with the path's heading. A landmark is *seen* from there when, with the
pan camera turned towards the board's centre as the wrappers' camera pointer turns it
(:class:`stsf_gym.estimators.camera_pointing.LandmarkPointer`), all of these hold:

1. range from the optical centre (``robot.camera_forward`` ahead of the axle) to the board's
   centre in ``[min_range, max_range]``;
2. viewing angle, between the board's normal and the direction to the camera, at most
   ``max_view_deg``;
3. the pan needed within ``robot.pan_limit_deg``;
4. the sight line, from the camera to the board, keeps at least half a wall thickness from
   every wall centre line and misses every obstacle's bounding circle;
5. the board's four corners project inside the image (camera at ``robot.camera_height``, no
   tilt, the env's width, height and vertical field of view);
6. its apparent size, the shorter of the mean projected width and height, is at least
   ``min_board_px`` pixels (the fast detector finds about 99 % of boards of 20 px).

A world passes when every sample sees at least one landmark.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from stsf_gym.envs.worlds.generator_config import VisibilityConfig

SIGHT_END = 0.15  # m: the sight line stops this short of the board (clear of its own wall)


@dataclass(frozen=True)
class CameraView:
    """What the check needs of the robot's camera (from an env config)."""

    width: int
    height: int
    vfov_deg: float
    camera_height: float
    camera_forward: float
    pan_limit_deg: float

    @classmethod
    def from_env_config(cls, cfg) -> CameraView:
        """The camera view of an env config ``cfg`` (its camera and mount)."""
        return cls(
            cfg.camera.width,
            cfg.camera.height,
            cfg.camera.vfov_deg,
            cfg.robot.camera_height,
            cfg.robot.camera_forward,
            cfg.robot.pan_limit_deg,
        )

    @property
    def focal_px(self) -> float:
        return (self.height / 2) / math.tan(math.radians(self.vfov_deg) / 2)


def path_samples(path: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Points (N, 2) along ``path`` every ``step`` metres and the heading (N,) at each; every
    vertex appears with the heading of each segment it joins."""
    points, headings = [], []
    for a, b in itertools.pairwise(path):
        length = float(np.linalg.norm(b - a))
        t = np.append(np.arange(0.0, length, step), length) / length
        points.append(a + t[:, None] * (b - a))
        headings.append(np.full(len(t), math.atan2(*(b - a)[::-1])))
    return np.concatenate(points), np.concatenate(headings)


def sample_arc_lengths(path: np.ndarray, step: float) -> np.ndarray:
    """Arc length (m, from the path's start) of each sample of :func:`path_samples`."""
    arcs, offset = [], 0.0
    for a, b in itertools.pairwise(path):
        length = float(np.linalg.norm(b - a))
        arcs.append(offset + np.append(np.arange(0.0, length, step), length))
        offset += length
    return np.concatenate(arcs)


def segment_distances(p0, p1, q0, q1) -> np.ndarray:
    """Distances between segments ``p0-p1`` (..., 2) and ``q0-q1`` (broadcast)."""
    d1, d2 = p1 - p0, q1 - q0

    def point_to(x, a, d):
        t = np.clip(np.sum((x - a) * d, -1) / np.maximum(np.sum(d * d, -1), 1e-12), 0, 1)
        return np.linalg.norm(x - a - t[..., None] * d, axis=-1)

    def cross(u, v):
        return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]

    denom = cross(d1, d2)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = cross(q0 - p0, d2) / denom
        u = cross(q0 - p0, d1) / denom
    crossing = (np.abs(denom) > 1e-12) & (s >= 0) & (s <= 1) & (u >= 0) & (u <= 1)
    nearest = np.minimum.reduce(
        [point_to(p0, q0, d2), point_to(p1, q0, d2), point_to(q0, p0, d1), point_to(q1, p0, d1)]
    )
    return np.where(crossing, 0.0, nearest)


def seen_matrix(
    samples: np.ndarray,
    headings: np.ndarray,
    boards: np.ndarray,
    normals: np.ndarray,
    walls: np.ndarray,
    obstacles: np.ndarray,
    thickness: float,
    board_size: float,
    board_height: float,
    view: CameraView,
    limits: VisibilityConfig,
) -> np.ndarray:
    """(samples x boards) bool: board seen from sample (module docstring). ``boards`` are the
    board centres (B, 2), ``normals`` their outward unit normals, ``walls`` (K, 4) centre
    lines, ``obstacles`` (M, 3) bounding circles ``x, y, radius``."""
    forward = np.stack([np.cos(headings), np.sin(headings)], axis=1)
    eye = samples + view.camera_forward * forward  # (N, 2)
    to_board = boards[None] - eye[:, None]  # (N, B, 2)
    distance = np.linalg.norm(to_board, axis=-1)
    unit = to_board / np.maximum(distance, 1e-9)[..., None]
    facing = -np.sum(unit * normals[None], axis=-1)
    pan = np.arctan2(unit[..., 1], unit[..., 0]) - headings[:, None]
    pan = np.abs(np.remainder(pan + np.pi, 2 * np.pi) - np.pi)
    seen = (distance >= limits.min_range) & (distance <= limits.max_range)
    seen &= facing >= math.cos(math.radians(limits.max_view_deg))
    seen &= pan <= math.radians(view.pan_limit_deg)
    seen &= _in_frame(distance, facing, board_size, board_height, view, limits)
    rows, cols = np.nonzero(seen)  # sight lines tested only where all else holds
    end = boards[cols] - SIGHT_END * unit[rows, cols]
    start = eye[rows]
    clear = np.ones(len(rows), bool)
    for wall in walls:
        clear &= segment_distances(start, end, wall[:2], wall[2:]) > thickness / 2
    for x, y, radius in obstacles:
        centre = np.array([x, y])
        clear &= segment_distances(start, end, centre, centre) > radius
    seen[rows[~clear], cols[~clear]] = False
    return seen


def _in_frame(distance, facing, size, board_height, view: CameraView, limits) -> np.ndarray:
    """Board corners inside the image and apparent size at least ``min_board_px``, for a
    camera looking straight at the board's centre (its plane seen at angle acos(facing))."""
    f = view.focal_px
    sin = np.sqrt(np.clip(1 - facing**2, 0, 1))
    half = size / 2
    # corners at +-half along the board (foreshortened, nearer/farther by half * sin)
    depth = np.stack([distance - half * sin, distance + half * sin])
    lateral = half * np.maximum(facing, 0)
    u = f * lateral / np.maximum(depth, 1e-6)  # |u| of the near and the far corners
    dz = view.camera_height - board_height
    v = f * np.stack([np.abs(dz - half), np.abs(dz + half)])[:, None, None] / depth[:, None]
    inside = (np.max(u, axis=0) <= view.width / 2) & (np.max(v, axis=(0, 1)) <= view.height / 2)
    width_px = np.mean(2 * u, axis=0)  # near and far vertical edges are 2u apart each
    height_px = np.mean(f * 2 * half / depth, axis=0)
    return inside & (np.minimum(width_px, height_px) >= limits.min_board_px)


def choose_landmarks(seen: np.ndarray, wanted: int) -> list[int] | None:
    """Greedy cover: candidate columns so every row sees ``min(wanted, what it can)`` of
    them, at least one; ``None`` if some row sees no candidate at all."""
    possible = seen.sum(axis=1)
    if np.any(possible == 0):
        return None
    target = np.minimum(possible, wanted)
    count = np.zeros(len(seen), int)
    chosen: list[int] = []
    while np.any(count < target):
        short = count < target
        gain = seen[short].sum(axis=0).astype(float)
        gain[chosen] = -1
        best = int(np.argmax(gain))
        chosen.append(best)
        count += seen[:, best]
    return sorted(chosen)
