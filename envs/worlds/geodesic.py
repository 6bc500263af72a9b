"""The geodesic length of a world's route: SPL's shortest path ``l`` (Anderson et al. 2018).

**Method.** The robot, a disc of radius ``r``, becomes a point once every footprint is grown by
``r`` (its configuration space, Lozano-Pérez & Wesley 1979): each wall is the box PyBullet
builds (:mod:`stsf_gym.envs.worlds.corridor`: the centre line lengthened by half a thickness
at both ends, ``wall_thickness`` thick), each obstacle its box or cylinder, each grown by ``r``
with round joins (shapely/GEOS ``buffer``) and all united. Among polygonal obstacles the
shortest path is a chain of straight segments between mutually visible convex corners of the
obstacles (the visibility graph: de Berg et al., *Computational Geometry*, 3rd ed., ch. 15),
searched with Dijkstra's algorithm. A route's length is the sum of its legs: the start to the
first goal, then goal to goal.

**Approximation.** GEOS draws each round join as :data:`QUAD_SEGS` segments per quarter
circle with their ends on the circle, so the computed obstacles lie inside the exact ones and
the computed length is never longer than the exact one. Every point of an exact arc of radius
``ρ`` lies within ``δ = ρ (1 - cos(π / (4 QUAD_SEGS)))`` of its polygon, so the exact
obstacles lie inside the computed ones grown by ``δ``; and a shortest path that turns by ``Θ``
in all around obstacle corners lengthens by ``δ Θ`` to first order when they grow by ``δ``
(the length's derivative in a corner's radius is the angle turned around it). Hence
``exact - δ Θ <= computed <= exact``: with ``QUAD_SEGS = 8``, ``δ`` is 0.48 % of ``ρ``,
1.2 mm for a wall corner (``ρ = r = 0.25 m``), so at most 1.9 mm short per right-angle turn.

**Start or goal inside the inflated obstacles** (the true start pose settles a few millimetres
off, or a goal lies nearer a wall than ``r``): the leg starts or ends at the nearest free point,
the nearest point of the inflated obstacles' boundary. **No path** (the start boxed in, a gap
narrower than the robot): :class:`ValueError` naming the world.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from itertools import pairwise

import numpy as np
import shapely
from shapely.affinity import rotate, translate
from shapely.geometry.polygon import orient

from stsf_gym.envs.config import ObstacleSpec, WorldConfig

QUAD_SEGS = 8  # segments per quarter circle of a round join (the approximation above)
#: m: a segment that touches the inflated obstacles' boundary (runs along it, grazes a corner)
#: is free; one that enters them by more than this is blocked
TOUCH_TOLERANCE = 1e-6


def arc_error_bound(radius: float) -> float:
    """``δ`` (m): how far an exact join of ``radius`` reaches beyond its polygon."""
    return radius * (1 - math.cos(math.pi / (4 * QUAD_SEGS)))


def inflated_obstacles(world: WorldConfig, body_radius: float) -> shapely.Geometry:
    """``world``'s walls and obstacles as PyBullet builds them, each grown by ``body_radius``,
    united: where the robot's centre cannot be."""
    half = world.wall_thickness / 2
    walls = [
        shapely.LineString([wall[:2], wall[2:]]).buffer(half, cap_style="square")
        for wall in world.walls
    ]
    grown = [wall.buffer(body_radius, quad_segs=QUAD_SEGS) for wall in walls]
    grown += [_inflated_obstacle(obstacle, body_radius) for obstacle in world.obstacles]
    return shapely.unary_union(grown)


def _inflated_obstacle(obstacle: ObstacleSpec, body_radius: float) -> shapely.Geometry:
    if obstacle.shape == "cylinder":
        centre = shapely.Point(obstacle.position)
        return centre.buffer(obstacle.size[0] + body_radius, quad_segs=QUAD_SEGS)
    length, width = obstacle.size[:2]
    box = rotate(shapely.box(-length / 2, -width / 2, length / 2, width / 2), obstacle.yaw_deg)
    return translate(box, *obstacle.position).buffer(body_radius, quad_segs=QUAD_SEGS)


def convex_corners(blocked: shapely.Geometry) -> np.ndarray:
    """The corners ``(N, 2)`` of ``blocked``'s polygons where they are convex: the only points
    at which a shortest path around them bends."""
    corners = []
    for polygon in shapely.get_parts(blocked):
        polygon = orient(polygon, sign=1.0)  # the obstacle on the left of every ring
        for ring in (polygon.exterior, *polygon.interiors):
            points = np.asarray(ring.coords)[:-1]
            incoming = points - np.roll(points, 1, axis=0)
            outgoing = np.roll(points, -1, axis=0) - points
            left_turn = incoming[:, 0] * outgoing[:, 1] - incoming[:, 1] * outgoing[:, 0] > 0
            corners.append(points[left_turn])
    return np.concatenate(corners) if corners else np.empty((0, 2))


class FreeSpace:
    """Where the centre of a disc robot of ``body_radius`` may be in ``world``, with the
    visibility graph among the inflated obstacles' convex corners (built once)."""

    def __init__(self, world: WorldConfig, body_radius: float) -> None:
        self.world_name, self.body_radius = world.name, body_radius
        self.blocked = inflated_obstacles(world, body_radius)
        self.interior = self.blocked.buffer(-TOUCH_TOLERANCE)
        shapely.prepare(self.interior)
        self.corners = convex_corners(self.blocked)
        first, second = np.triu_indices(len(self.corners), 1)
        self.corner_graph = np.full((len(self.corners),) * 2, np.inf)
        lengths = self.free_lengths(self.corners[first], self.corners[second])
        self.corner_graph[first, second] = self.corner_graph[second, first] = lengths

    def free_lengths(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """The length of each straight segment ``starts[i]`` to ``ends[i]``, inf where it
        enters the inflated obstacles."""
        segments = shapely.linestrings(np.stack([starts, ends], axis=1))
        lengths = np.linalg.norm(ends - starts, axis=-1)
        return np.where(shapely.intersects(segments, self.interior), np.inf, lengths)

    def nearest_free(self, point: Sequence[float]) -> np.ndarray:
        """``point`` itself when free, else the nearest point of the obstacles' boundary."""
        if not self.interior.contains(shapely.Point(point)):
            return np.asarray(point, dtype=float)
        nearest = shapely.shortest_line(self.blocked.boundary, shapely.Point(point))
        return np.asarray(nearest.coords[0])

    def shortest_length(self, start: Sequence[float], goal: Sequence[float]) -> float:
        """The length (m) of the shortest collision-free path from ``start`` to ``goal``."""
        ends = np.array([self.nearest_free(start), self.nearest_free(goal)])
        direct = self.free_lengths(ends[:1], ends[1:])[0]
        if np.isfinite(direct):
            return float(direct)
        count = len(self.corners)
        graph = np.full((count + 2, count + 2), np.inf)
        graph[2:, 2:] = self.corner_graph
        to_corners = self.free_lengths(np.repeat(ends, count, 0), np.tile(self.corners, (2, 1)))
        graph[:2, 2:] = to_corners.reshape(2, count)
        graph[2:, :2] = graph[:2, 2:].T
        from scipy.sparse.csgraph import dijkstra  # here: the env's import path stays SciPy-free

        length = float(dijkstra(graph, directed=False, indices=0)[1])
        if not np.isfinite(length):
            raise ValueError(
                f"world {self.world_name!r}: no collision-free path for a robot of radius "
                f"{self.body_radius:g} m from {ends[0].tolist()} to {ends[1].tolist()}"
            )
        return length


def route_geodesic_length(
    world: WorldConfig,
    start: Sequence[float],
    body_radius: float,
    goals: Sequence[Sequence[float]] | np.ndarray | None = None,
) -> float:
    """The length (m) of the shortest collision-free route from ``start`` (x, y) through
    ``goals`` in order (default: the world's, :attr:`WorldConfig.goals`) for a disc robot of
    ``body_radius``."""
    space = FreeSpace(world, body_radius)
    stops = [start, *(world.goals if goals is None else goals)]
    return sum(space.shortest_length(a, b) for a, b in pairwise(stops))


def connected_to_path(world: WorldConfig, body_radius: float, point: Sequence[float]) -> bool:
    """Whether a robot of ``body_radius`` at ``point`` could drive to the path's start: the
    free space around ``point`` is the corridor's, not a pocket between walls or outside them
    (inside the walls' bounding box all the same)."""
    blocked = inflated_obstacles(world, body_radius)
    low, high = np.min(world.path, axis=0) - 1e3, np.max(world.path, axis=0) + 1e3
    free = shapely.box(*low, *high).difference(blocked)
    start = shapely.Point(world.path[0])
    parts = getattr(free, "geoms", [free])
    corridor = next((part for part in parts if part.covers(start)), None)
    return corridor is None or bool(corridor.covers(shapely.Point(point)))
