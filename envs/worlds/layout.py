"""Corridor networks as unions of axis-aligned rectangles, and the walls around them.

A corridor leg is a rectangle of free space; the walls are the boundary of the union of all
legs, each leg grown by half a wall thickness so that the wall faces sit on the free space.
The boundary is exact: coordinate compression turns the rectangles into a grid of cells,
every cell edge between a free and a walled cell is a piece of wall, and collinear pieces
facing the same way merge into one segment.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DIRECTIONS = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])  # east, north, ...
DECIMALS = 6  # coordinates are rounded to this many decimals (exact grid arithmetic)


@dataclass(frozen=True)
class Rect:
    """Axis-aligned rectangle ``[xmin, ymin, xmax, ymax]`` of free space."""

    xmin: float
    ymin: float
    xmax: float
    ymax: float

    @classmethod
    def around(cls, a, b, half_width: float, back: float, ahead: float) -> Rect:
        """Free space of a leg along the axis-aligned centre line ``a -> b``, ``half_width``
        to either side, extended ``back`` behind ``a`` and ``ahead`` beyond ``b``."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        direction = (b - a) / np.linalg.norm(b - a)
        across = np.abs(direction[::-1]) * half_width
        p, q = a - back * direction, b + ahead * direction
        low, high = np.minimum(p, q) - across, np.maximum(p, q) + across
        return cls(*np.round([low[0], low[1], high[0], high[1]], DECIMALS))

    def grown(self, margin: float) -> Rect:
        """This rectangle grown by ``margin`` (m) on every side."""
        return Rect(self.xmin - margin, self.ymin - margin, self.xmax + margin, self.ymax + margin)

    def gap(self, other: Rect) -> float:
        """Distance between the two rectangles (0 when they touch or overlap)."""
        dx = max(other.xmin - self.xmax, self.xmin - other.xmax, 0.0)
        dy = max(other.ymin - self.ymax, self.ymin - other.ymax, 0.0)
        return float(np.hypot(dx, dy))


def boundary_walls(rects: list[Rect], thickness: float) -> list[tuple[tuple, tuple]]:
    """Wall centre lines around the union of ``rects`` (each grown by ``thickness / 2``).

    Returns ``(segment, inward)`` pairs: ``segment = (x1, y1, x2, y2)``, ``inward`` the unit
    normal (x, y) pointing into the free space.
    """
    grown = [r.grown(thickness / 2) for r in rects]
    xs = np.unique(np.round([v for r in grown for v in (r.xmin, r.xmax)], DECIMALS))
    ys = np.unique(np.round([v for r in grown for v in (r.ymin, r.ymax)], DECIMALS))
    cx, cy = (xs[:-1] + xs[1:]) / 2, (ys[:-1] + ys[1:]) / 2
    inside = np.zeros((len(cx) + 2, len(cy) + 2), bool)  # padded with walled cells
    for r in grown:
        inside[1:-1, 1:-1] |= ((cx > r.xmin) & (cx < r.xmax))[:, None] & (
            (cy > r.ymin) & (cy < r.ymax)
        )[None, :]
    walls = []
    # vertical pieces at x = xs[i], between cell columns i - 1 and i (padded: i and i + 1)
    change = inside[1:, 1:-1] != inside[:-1, 1:-1]  # (len(xs), len(cy))
    for i, x in enumerate(xs):
        walls += _runs(change[i], inside[i + 1, 1:-1], ys, lambda a, b, x=x: (x, a, x, b), 0)
    change = inside[1:-1, 1:] != inside[1:-1, :-1]  # (len(cx), len(ys))
    for j, y in enumerate(ys):
        walls += _runs(change[:, j], inside[1:-1, j + 1], xs, lambda a, b, y=y: (a, y, b, y), 1)
    return walls


def _runs(change, free_after, edges, segment, axis: int) -> list[tuple[tuple, tuple]]:
    """Merge consecutive wall pieces that face the same way into segments."""
    found, start = [], None
    for k in range(len(change) + 1):
        key = (bool(free_after[k])) if k < len(change) and change[k] else None
        if start is not None and key != start[1]:
            inward = [0.0, 0.0]
            inward[axis] = 1.0 if start[1] else -1.0
            coords = tuple(float(v) for v in np.round(segment(edges[start[0]], edges[k]), 6))
            found.append((coords, tuple(inward)))
            start = None
        if key is not None and start is None:
            start = (k, key)
    return found
