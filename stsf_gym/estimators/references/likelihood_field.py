"""The map's walls as a likelihood field, and the free space a robot may stand in.

A grid of ``resolution`` over the walls' bounds holds in each cell the distance (m) to the
nearest wall face (a wall is its centre-line segment, its faces ``wall_thickness / 2`` off it).
A sonar reading ``r`` of transducer ``a`` ends at ``x (+) (ring (+) r)``; the likelihood field
model (Thrun, Burgard and Fox, *Probabilistic Robotics*, sect. 6.4) scores it by that end
point's distance ``d`` to the nearest wall::

    p(r | x, map) = z_hit N(d; 0, sigma^2) + z_rand / r_max

with ``z_rand`` = ``sonar_random`` and ``z_hit = 1 - z_rand``; readings at ``r_max`` (no echo)
are left out. The *free space* is the cells at least the robot's body radius from every wall
face and connected to the start cell: the inside of the map, not the outside of its walls.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from stsf_gym.estimators.base import SensorModel

MARGIN = 1.0  # m of grid beyond the walls' bounds


class LikelihoodField:
    """``distance(points)``: distance (m) to the nearest wall face, for points ``(..., 2)``
    (beyond the grid: the grid's edge value); ``sample_free(n, rng)``: uniform free poses."""

    def __init__(self, model: SensorModel, resolution: float, start_xy) -> None:
        walls = np.asarray(model.walls, dtype=float)
        self.resolution = resolution
        self.origin = walls.reshape(-1, 2).min(axis=0) - MARGIN
        top = walls.reshape(-1, 2).max(axis=0) + MARGIN
        self.shape = tuple(np.ceil((top - self.origin) / resolution).astype(int) + 1)
        gx, gy = np.meshgrid(*(np.arange(n) for n in self.shape), indexing="ij")
        centres = self.origin + resolution * np.stack([gx, gy], axis=-1)
        self.grid = np.maximum(_segment_distance(centres, walls) - model.wall_thickness / 2, 0.0)
        clear, _ = ndimage.label(self.grid >= model.body_radius)
        start = self._cell(np.asarray(start_xy, dtype=float)[:2])
        label = clear[tuple(start)]
        self.free = np.argwhere(clear == label) if label else np.argwhere(clear > 0)

    def _cell(self, points: np.ndarray) -> np.ndarray:
        cells = np.rint((points - self.origin) / self.resolution).astype(int)
        return np.clip(cells, 0, np.array(self.shape) - 1)

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Distance (m) from ``points`` (..., 2) to the nearest wall face, looked up in the grid."""
        cells = self._cell(points)
        return self.grid[cells[..., 0], cells[..., 1]]

    def sample_free(self, count: int, rng: np.random.Generator) -> np.ndarray:
        """``count`` poses uniform over the free space (within a cell) and in heading."""
        cells = self.free[rng.integers(len(self.free), size=count)]
        xy = self.origin + self.resolution * (cells + rng.uniform(-0.5, 0.5, (count, 2)))
        return np.column_stack([xy, rng.uniform(-np.pi, np.pi, count)])


def _segment_distance(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Distance of each point ``(..., 2)`` to the nearest segment ``(K, 4)``."""
    best = np.full(points.shape[:-1], np.inf)
    for x1, y1, x2, y2 in segments:
        a, d = np.array([x1, y1]), np.array([x2 - x1, y2 - y1])
        t = np.clip(((points - a) @ d) / max(d @ d, 1e-12), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points - a - t[..., None] * d, axis=-1))
    return best
