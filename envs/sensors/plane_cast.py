"""The sonar's rays cast in the plane of the ring, against the world's footprints there.

Every collision shape of a world stands upright on the floor (walls and clutter are boxes
turned about z, pillars are cylinders), so at the ring's height ``h`` a shape is a rectangle or
a circle, or nothing where it does not reach ``h``. A horizontal ray meets an upright shape
where it meets its footprint, and the face it meets is vertical, so its normal lies in the
plane: the 2-D cast gives PyBullet's ``rayTestBatch`` hit (fraction of the ray and normal)
exactly, up to rounding, for all the rays of a ring at once in numpy.

A ray ``o + t d`` (``|d| = 1``, ``0 <= t <= L``) meets a footprint edge ``p + u e`` (``0 <= u
<= 1``) at ``t = (p - o) x e / (d x e)``, ``u = (p - o) x d / (d x e)``, where the edge faces
the ray (``d . n < 0``, ``n`` its outward normal); a circle of centre ``c`` and radius ``r`` at
``t = -b - sqrt(b^2 - |o - c|^2 + r^2)``, ``b = d . (o - c)``. The nearest such ``t`` is the
hit; its fraction ``t / L``, its normal the edge's ``n`` or ``(o + t d - c) / r``.
"""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.envs.rendering.scene import Box, Cylinder, Scene
from stsf_gym.geometry import compiled

#: outward normals of a box's four faces in its own frame, and the corner each face starts at
FACE_NORMALS = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
FACE_STARTS = np.array([[1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0]])
#: How far (m) the ring may move before the edges in its reach are selected again: they are
#: selected for ``reach + REACH_MARGIN``, a superset of the edges any ray can enter until then
REACH_MARGIN = 0.5


class PlaneCaster:
    """Ray casts at height ``height`` against a :class:`Scene`'s shown shapes; the footprints
    are rebuilt only when the scene changes (:attr:`Scene.version`)."""

    def __init__(self, height: float) -> None:
        self.height = height
        self._built: tuple[int, int] | None = None  # (id of the scene, its version)
        self._selection: tuple[np.ndarray, float, np.ndarray] | None = None  # centre, reach, edges

    def cast(
        self,
        scene: Scene,
        centre: np.ndarray,
        starts: np.ndarray,
        directions: np.ndarray,
        length: float,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Hit fraction of ``length`` (1: no hit) and 2-D hit normal (0 without a hit) of each
        ray from ``starts`` (N, 2), all within ``self``'s ring of ``centre``, along unit
        ``directions`` (N, 2)."""
        self._footprints(scene)
        t = np.full(len(starts), np.inf)
        normals = np.zeros((len(starts), 2))
        edges = self._reachable(centre, np.hypot(*(starts - centre).T).max() + length)
        if len(edges):
            _edge_hits(edges, starts, directions, t, normals)
        if len(self._circles):
            _circle_hits(self._circles, starts, directions, t, normals)
        return _hit_fractions(t, normals, length), normals

    def _reachable(self, centre: np.ndarray, reach: float) -> np.ndarray:
        """Edges, in their order, among which are all a ray from within ``reach`` of
        ``centre`` can enter: :meth:`_select`'s for a wider reach about a nearby centre, kept
        while ``centre`` is within the difference (an edge's distance and the side of it a
        point is on change no faster than the point moves). Edges out of reach meet no ray
        before its end, so a superset gives the same nearest hits."""
        if self._selection is not None:
            selected_at, selected_reach, edges = self._selection
            moved = math.hypot(centre[0] - selected_at[0], centre[1] - selected_at[1])
            if moved <= selected_reach - reach:
                return edges
        edges = self._select(centre, reach + REACH_MARGIN)
        self._selection = (centre.copy(), reach + REACH_MARGIN, edges)
        return edges

    def _select(self, centre: np.ndarray, reach: float) -> np.ndarray:
        """The edges a ray from within ``reach`` of ``centre`` can enter: those nearer than
        ``reach`` whose outside faces ``centre`` or passes within ``reach`` of it (a wall's
        far face is out of every ray's reach from the corridor: half the edges)."""
        p, e, n = self._edges[:, 0:2], self._edges[:, 2:4], self._edges[:, 4:6]
        to_centre = centre - p
        along = np.clip(np.sum(to_centre * e, axis=1) / np.sum(e * e, axis=1), 0.0, 1.0)
        gap = np.hypot(*(to_centre - along[:, None] * e).T)
        return self._edges[(gap <= reach) & (np.sum(to_centre * n, axis=1) > -reach)]

    def _footprints(self, scene: Scene) -> None:
        """Edges (start, edge vector, outward normal) of the shown boxes and circles (centre,
        radius) of the shown cylinders that reach the ring's height."""
        if self._built == (id(scene), scene.version):
            return
        edges, circles = [np.zeros((0, 6))], []
        for body, shape in scene.shapes.items():
            if body in scene.hidden:
                continue
            if isinstance(shape, Box) and _spans(shape.centre[2], shape.half[2], self.height):
                edges.append(_box_edges(shape))
            elif isinstance(shape, Cylinder) and 0.0 <= self.height <= shape.height:
                circles.append([*shape.xy, shape.radius])
        self._edges = np.concatenate(edges)
        self._selection = None
        self._circles = np.array(circles, dtype=float).reshape(-1, 3)
        self._built = (id(scene), scene.version)


@compiled
def _hit_fractions(t: np.ndarray, normals: np.ndarray, length: float) -> np.ndarray:
    """Each ray's hit as a fraction of ``length``, 1 where it met nothing within it (its normal
    then zeroed in place): ``np.where(t <= length, t / length, 1.0)``."""
    fractions = np.ones(len(t))
    for i in range(len(t)):
        if t[i] <= length:
            fractions[i] = t[i] / length
        else:
            normals[i, 0], normals[i, 1] = 0.0, 0.0
    return fractions


@compiled
def _edge_hits(
    edges: np.ndarray, o: np.ndarray, d: np.ndarray, t: np.ndarray, normals: np.ndarray
) -> None:
    """The nearest edge (rows ``[p, e, n]``) each ray ``o + t d`` enters, where nearer than
    its ``t`` (``t`` and ``normals`` updated in place): ``t = (p x e - o x e) / (d x e)``, ``u
    = (p x d - o x d) / (d x e)`` with ``a x b = a_x b_y - a_y b_x``; the first of equal
    nearest edges wins."""
    for i in range(o.shape[0]):
        ox, oy, dx, dy = o[i, 0], o[i, 1], d[i, 0], d[i, 1]
        best, nearest = np.inf, -1
        for j in range(edges.shape[0]):
            px, py, ex, ey, nx, ny = edges[j]
            if not dx * nx + dy * ny < 0:  # the edge's outside is away from the ray
                continue
            denominator = dx * ey - dy * ex
            along = (px * ey - py * ex - (ox * ey - oy * ex)) / denominator
            across = (px * dy - py * dx - (ox * dy - oy * dx)) / denominator
            if along >= 0 and 0 <= across <= 1 and along < best:
                best, nearest = along, j
        if nearest >= 0 and best < t[i]:
            t[i] = best
            normals[i, 0], normals[i, 1] = edges[nearest, 4], edges[nearest, 5]


@compiled
def _circle_hits(
    circles: np.ndarray, o: np.ndarray, d: np.ndarray, t: np.ndarray, normals: np.ndarray
) -> None:
    """The nearest circle (rows ``[c, r]``) each ray enters, where nearer than its ``t``
    (``t`` and ``normals`` updated in place): ``t = -b - sqrt(b^2 - |o - c|^2 + r^2)``, ``b =
    d . (o - c)``, normal ``(o + t d - c) / r``; the first of equal nearest circles wins."""
    for i in range(o.shape[0]):
        best, nearest = np.inf, -1
        for j in range(circles.shape[0]):
            cx, cy, r = circles[j]
            ocx, ocy = o[i, 0] - cx, o[i, 1] - cy
            b = d[i, 0] * ocx + d[i, 1] * ocy
            disc = b * b - (ocx * ocx + ocy * ocy) + r**2
            if disc >= 0:
                along = -b - np.sqrt(disc)
                if along >= 0 and along < best:
                    best, nearest = along, j
        if nearest >= 0 and best < t[i]:
            t[i] = best
            cx, cy, r = circles[nearest]
            normals[i, 0] = (o[i, 0] + best * d[i, 0] - cx) / r
            normals[i, 1] = (o[i, 1] + best * d[i, 1] - cy) / r


def _spans(centre: float, half: float, height: float) -> bool:
    """Whether a shape from ``centre - half`` to ``centre + half`` reaches ``height``."""
    return centre - half <= height <= centre + half


def _box_edges(box: Box) -> np.ndarray:
    """The four faces of ``box``'s footprint: start corner, edge vector, outward normal."""
    c, s = np.cos(box.yaw), np.sin(box.yaw)
    rotation = np.array([[c, -s], [s, c]])
    half = np.asarray(box.half[:2], dtype=float)
    starts = (FACE_STARTS * half) @ rotation.T + box.centre[:2]
    ends = np.roll(starts, -1, axis=0)
    return np.hstack([starts, ends - starts, FACE_NORMALS @ rotation.T])
