"""The landmark pattern of the paper's Fig. 3: white squares on black, with an id code.

A landmark is a ``grid x grid`` array of cells at ``pitch`` spacing; a white square of
side ``square_size`` sits in the centre of a cell when that cell is lit. The outer ring of
cells and the centre cell are always lit: that is the symmetric, repetitive part the
template matcher looks for. The remaining inner cells carry the landmark id as bits, read
row by row from the top left (bit 0 first), so a detector that has found the ring reads the
id from which inner squares are present.

Coordinates are in the landmark plane, in metres, origin at the board centre, ``x`` to the
right and ``y`` up as seen by a viewer facing the landmark. The same functions give the
texture the simulator pastes on the wall and the geometry the detector matches against.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LandmarkPattern:
    """Geometry of the landmark board (metres)."""

    square_size: float = 0.05
    pitch: float = 0.10
    grid: int = 5
    border: float = 0.05

    def __post_init__(self) -> None:
        if self.grid < 3:
            raise ValueError(f"landmark grid must be at least 3, got {self.grid}")
        if not 0 < self.square_size < self.pitch:
            raise ValueError(
                f"landmark square_size ({self.square_size}) must be in (0, pitch={self.pitch})"
            )
        if self.border < 0:
            raise ValueError(f"landmark border must be >= 0, got {self.border}")

    @property
    def size(self) -> float:
        """Side of the whole (square) black board."""
        return (self.grid - 1) * self.pitch + self.square_size + 2 * self.border

    @property
    def id_cells(self) -> list[tuple[int, int]]:
        """Inner cells (row, col) that carry id bits, in bit order."""
        centre = self.grid // 2
        return [
            (r, c)
            for r in range(1, self.grid - 1)
            for c in range(1, self.grid - 1)
            if (r, c) != (centre, centre)
        ]

    @property
    def max_id(self) -> int:
        return 2 ** len(self.id_cells) - 1


def lit_cells(landmark_id: int, pattern: LandmarkPattern) -> list[tuple[int, int]]:
    """Cells (row, col) holding a white square for ``landmark_id``, in row-major order."""
    if not 0 <= landmark_id <= pattern.max_id:
        raise ValueError(f"landmark id {landmark_id} outside 0..{pattern.max_id} for this grid")
    g, centre = pattern.grid, pattern.grid // 2
    bits = {cell for i, cell in enumerate(pattern.id_cells) if landmark_id >> i & 1}
    return [
        (r, c)
        for r in range(g)
        for c in range(g)
        if r in (0, g - 1) or c in (0, g - 1) or (r, c) == (centre, centre) or (r, c) in bits
    ]


def decode_landmark_id(lit: set[tuple[int, int]], pattern: LandmarkPattern) -> int:
    """Inverse of :func:`lit_cells`: the id whose bits are the lit inner cells."""
    return sum(1 << i for i, cell in enumerate(pattern.id_cells) if cell in lit)


def cell_centre(row: int, col: int, pattern: LandmarkPattern) -> np.ndarray:
    """Centre of cell (row, col) in landmark-plane coordinates (row 0 is the top)."""
    half = (pattern.grid - 1) / 2
    return np.array([(col - half) * pattern.pitch, (half - row) * pattern.pitch])


def square_centres(landmark_id: int, pattern: LandmarkPattern) -> np.ndarray:
    """(M, 2) centres of the white squares, in the order of :func:`lit_cells` (a fresh copy of
    the table made once per id and pattern: estimators ask for it every frame)."""
    return _square_centres(landmark_id, pattern).copy()


@functools.lru_cache(maxsize=4096)
def _square_centres(landmark_id: int, pattern: LandmarkPattern) -> np.ndarray:
    return np.array([cell_centre(r, c, pattern) for r, c in lit_cells(landmark_id, pattern)])


def square_corners(landmark_id: int, pattern: LandmarkPattern) -> np.ndarray:
    """(M, 4, 2) corners of each white square: top-left, top-right, bottom-right, bottom-left."""
    h = pattern.square_size / 2
    offsets = np.array([[-h, h], [h, h], [h, -h], [-h, -h]])
    return square_centres(landmark_id, pattern)[:, None, :] + offsets[None]


def board_corners(pattern: LandmarkPattern) -> np.ndarray:
    """(4, 2) outer corners of the black board: top-left, top-right, bottom-right, bottom-left."""
    h = pattern.size / 2
    return np.array([[-h, h], [h, h], [h, -h], [-h, -h]])


def landmark_image(landmark_id: int, pattern: LandmarkPattern, px_per_m: float = 480.0):
    """Greyscale uint8 image of the board, white squares (255) on black (0).

    The pixel grid is aligned so square edges fall on pixel boundaries where
    ``square_size * px_per_m`` is whole; row 0 is the top of the board.
    """
    n = round(pattern.size * px_per_m)
    image = np.zeros((n, n), dtype=np.uint8)
    scale = n / pattern.size
    for corners in square_corners(landmark_id, pattern):
        left, top = corners[0]
        right, bottom = corners[2]
        c0, c1 = (np.array([left, right]) + pattern.size / 2) * scale
        r0, r1 = (pattern.size / 2 - np.array([top, bottom])) * scale
        image[round(r0) : round(r1), round(c0) : round(c1)] = 255
    return image
