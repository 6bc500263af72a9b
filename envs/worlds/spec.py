"""A world's schema and the geometry that makes it valid: :class:`WorldConfig` (walls, path,
route, start, landmarks, clutter), and the checks its construction runs (landmarks on walls,
start and path clear of walls, the route on the path).

:func:`check_start_pose` also checks ``reset(options={"start_pose": ...})``.

The checks raise :class:`~stsf_gym.validation.FieldError` naming the key relative to the config
being checked (``landmarks[2].at`` in a world, ``world.start`` in the whole env config), so
:func:`~stsf_gym.validation.build` reports the full key path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np

from stsf_gym.validation import (
    WORLD_EXTENT_M,
    Coordinate,
    Degrees,
    FieldError,
    Range,
    WorldLength,
    require,
)
from stsf_gym.vision.landmarks import LandmarkPattern

ON_WALL_TOLERANCE = 1e-3  # m: how far a landmark's ``at`` may be off a wall centre line
SQUARE_TOLERANCE_DEG = 1.0  # how far a landmark's normal may be off square to its wall
SIDES = (-math.pi / 2, math.pi / 2)  # the two normals of a wall, from its direction


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
    landmarks, checked on construction (the functions below).
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


def segment_distance(point, segment) -> float:
    """Distance from ``point`` (x, y) to the segment ``[x1, y1, x2, y2]``."""
    p, a, b = np.asarray(point, float), np.asarray(segment[:2], float), np.asarray(segment[2:])
    ab = b - a
    t = np.clip(np.dot(p - a, ab) / np.dot(ab, ab), 0.0, 1.0)
    return float(np.hypot(*(p - a - t * ab)))


def obstacle_distance(point, obstacle: ObstacleSpec) -> float:
    """Distance from ``point`` to an obstacle's footprint (0 inside it)."""
    offset = np.asarray(point, float) - obstacle.position
    if obstacle.shape == "cylinder":
        return max(0.0, float(np.hypot(*offset)) - obstacle.size[0])
    yaw = math.radians(obstacle.yaw_deg)
    c, s = math.cos(yaw), math.sin(yaw)
    local = np.array([c * offset[0] + s * offset[1], -s * offset[0] + c * offset[1]])
    outside = np.maximum(np.abs(local) - np.asarray(obstacle.size[:2]) / 2, 0.0)
    return float(np.hypot(*outside))


def check_world(world: WorldConfig) -> None:
    """Walls have length, the path two points, landmarks sit on walls and fit on them."""
    for i, wall in enumerate(world.walls):
        require(wall[:2] != wall[2:], f"walls[{i}]", f"must join two different points, got {wall}")
    pattern = world.landmark_pattern
    ids = [lm.id for lm in world.landmarks]
    for i, landmark in enumerate(world.landmarks):
        require(
            landmark.id <= pattern.max_id,
            f"landmarks[{i}].id",
            f"must be in [0, {pattern.max_id}] for a {pattern.grid}x{pattern.grid} grid, "
            f"got {landmark.id}",
        )
        require(
            landmark.id not in ids[:i],
            f"landmarks[{i}].id",
            f"must be unique, got {landmark.id} again (ids: {ids})",
        )
        _check_on_wall(world, i)
    _check_boards_apart(world)
    half = pattern.size / 2
    require(
        half <= world.landmark_height <= world.wall_height - half,
        "landmark_height",
        f"must be in [{half:g}, {world.wall_height - half:g}] so a {pattern.size:g} m board fits "
        f"on a {world.wall_height:g} m wall, got {world.landmark_height}",
    )
    for i, obstacle in enumerate(world.obstacles):
        entries = 3 if obstacle.shape == "box" else 2
        require(
            len(obstacle.size) == entries,
            f"obstacles[{i}].size",
            f"of a {obstacle.shape} must have {entries} entries, got {list(obstacle.size)}",
        )


def _check_on_wall(world: WorldConfig, index: int) -> None:
    landmark = world.landmarks[index]
    check_board_on_wall(world, landmark.at, landmark.facing_deg, f"landmarks[{index}]")


def check_board_on_wall(world: WorldConfig, at, facing_deg: float, key: str) -> None:
    """A board (a landmark, a decoy) centred at ``at`` on a wall centre line of ``world``,
    facing straight out of it; :class:`FieldError` naming ``key.at`` or ``key.facing_deg``."""
    distances = [segment_distance(at, wall) for wall in world.walls]
    nearest = int(np.argmin(distances))
    require(
        distances[nearest] <= ON_WALL_TOLERANCE,
        f"{key}.at",
        f"must lie on a wall centre line (the nearest, walls[{nearest}], is "
        f"{distances[nearest]:.3f} m away), got {list(at)}",
    )
    squares = []
    for wall, distance in zip(world.walls, distances, strict=True):
        if distance <= ON_WALL_TOLERANCE:
            along = math.atan2(wall[3] - wall[1], wall[2] - wall[0])
            squares += [math.degrees(math.remainder(along + s, math.tau)) for s in SIDES]
    off = min(abs(math.remainder(facing_deg - s, 360.0)) for s in squares)
    require(
        off <= SQUARE_TOLERANCE_DEG,
        f"{key}.facing_deg",
        f"must face straight out of its wall ({' or '.join(f'{s:g}' for s in squares)}), "
        f"got {facing_deg:g}",
    )


def _check_boards_apart(world: WorldConfig) -> None:
    """Two boards on one face of a wall (facing the same way) hang a board's width apart at
    least: closer, they overlap and neither pattern can be read."""
    size = world.landmark_pattern.size
    landmarks = world.landmarks
    for j, second in enumerate(landmarks):
        for i, first in enumerate(landmarks[:j]):
            same_face = abs(math.remainder(first.facing_deg - second.facing_deg, 360.0)) < 90
            gap = math.dist(first.at, second.at)
            require(
                not (same_face and gap < size - ON_WALL_TOLERANCE),
                f"landmarks[{j}].at",
                f"overlaps landmarks[{i}] on its wall: centres {gap:.3f} m apart, a "
                f"{size:g} m board needs {size:g} m, got {list(second.at)}",
            )


def path_arc_length(path, point) -> tuple[float, float]:
    """Arc length along ``path`` of the path point nearest ``point``, and the distance to it."""
    path, p = np.asarray(path, float), np.asarray(point, float)[:2]
    a, d = path[:-1], np.diff(path, axis=0)
    lengths = np.linalg.norm(d, axis=1)
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.maximum(lengths**2, 1e-12), 0.0, 1.0)
    gaps = np.linalg.norm(p - a - t[:, None] * d, axis=1)
    i = int(np.argmin(gaps))
    return float(np.sum(lengths[:i]) + t[i] * lengths[i]), float(gaps[i])


def check_route(world: WorldConfig) -> None:
    """Each route goal lies on the path, further along than the one before; the last is the
    path's end (the route is what the ``declare`` task visits, in order)."""
    previous = -math.inf
    for i, goal in enumerate(world.route):
        along, gap = path_arc_length(world.path, goal)
        require(gap <= ON_WALL_TOLERANCE, f"route[{i}]", f"must lie on the path, {gap:.3f} m off")
        require(along > previous, f"route[{i}]", "must lie further along the path than route[i-1]")
        previous = along
    if world.route:
        end = np.asarray(world.path[-1], float)
        require(
            bool(np.allclose(world.route[-1], end, atol=ON_WALL_TOLERANCE)),
            f"route[{len(world.route) - 1}]",
            f"the last goal must be the path's end {end.tolist()}, got {list(world.route[-1])}",
        )


def check_clearance(world: WorldConfig, body_radius: float) -> None:
    """Start pose and path points inside the walls' bounds, a robot radius clear of walls.

    Keys are relative to the env config (``world.start``, ``world.path[1]``).
    """
    check_start_pose(world, world.start, body_radius, "world.start")
    for i, point in enumerate(world.path):
        _check_clear_of_walls(world, point, body_radius, f"world.path[{i}]")


#: rad: the largest start yaw taken (two turns either way); a larger one is a unit mistake or a
#: typo, not an angle (1e12 rad wraps to a float-rounding accident).
YAW_LIMIT = 4 * math.pi


def check_start_pose(world: WorldConfig, pose, body_radius: float, key: str) -> np.ndarray:
    """``pose`` as three finite numbers ``[x, y, yaw]`` (yaw within :data:`YAW_LIMIT`) inside
    the walls' bounds and a robot radius clear of walls and obstacles; a :class:`FieldError`
    naming ``key`` otherwise."""
    try:
        pose = np.asarray(pose, dtype=float)
    except (TypeError, ValueError):
        raise FieldError(key, f"must be three finite numbers [x, y, yaw], got {pose!r}") from None
    require(
        pose.shape == (3,) and bool(np.all(np.isfinite(pose))),
        key,
        f"must be three finite numbers [x, y, yaw], got {pose.tolist()}",
    )
    require(
        abs(pose[2]) <= YAW_LIMIT,
        key,
        f"yaw must be an angle in radians within ±{YAW_LIMIT:.4g} (two turns), got {pose[2]:g}",
    )
    _check_clear_of_walls(world, pose[:2], body_radius, key)
    for i, obstacle in enumerate(world.obstacles):
        gap = obstacle_distance(pose[:2], obstacle)
        require(
            gap >= body_radius,
            key,
            f"must be at least robot.body_radius ({body_radius:g} m) from every obstacle; "
            f"obstacles[{i}] is {gap:.3f} m away from {pose[:2].tolist()}",
        )
    return pose


def _check_clear_of_walls(world: WorldConfig, point, body_radius: float, key: str) -> None:
    ends = np.array([p for wall in world.walls for p in (wall[:2], wall[2:])])
    low, high = ends.min(axis=0), ends.max(axis=0)
    require(
        bool(np.all((low <= point) & (point <= high))),
        key,
        f"must be inside the walls' bounds x in [{low[0]:g}, {high[0]:g}], "
        f"y in [{low[1]:g}, {high[1]:g}], got {list(point)}",
    )
    gaps = [segment_distance(point, w) - world.wall_thickness / 2 for w in world.walls]
    nearest = int(np.argmin(gaps))
    require(
        gaps[nearest] >= body_radius,
        key,
        f"must be at least robot.body_radius ({body_radius:g} m) from every wall; "
        f"walls[{nearest}] is {gaps[nearest]:.3f} m away from {list(point)}",
    )
