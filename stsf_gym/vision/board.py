"""Stage 2 of the landmark detector: the board's geometry in a region of interest.

The board is the 8-connected dark region enclosing the most holes (4-connected bright
regions), read from the two-level contour hierarchy of the dark pixels. The white squares
are the bright blobs inside its convex hull (far away the black border can be thinner than
a pixel, so outer squares are not always holes). The four corner squares of the always-lit
outer ring (extreme along the image diagonals) give a first homography from the landmark
plane, which assigns every blob to a grid cell; all ring cells and the centre must be
present, no blob may be left over, and the lit inner cells give the id (bit ``i`` is cell
``pattern.id_cells[i]``, as :func:`~stsf_gym.vision.landmarks.decode_landmark_id`). Each
square's centre is then the intensity-weighted centroid (above the board's black level) of
a window around its blob, a homography is fitted to all squares by least squares, and the
board is rejected when its reprojection error is too large.

Cost: one threshold and one contour pass per region; the rest works on the board's box and
handles all squares at once (window sums from one integral image), with no loop over them.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import cv2
import numpy as np

from stsf_gym.vision.landmarks import LandmarkPattern, board_corners, cell_centre

__all__ = ["GROW", "BoardFit", "BoardFitter", "apply_homography"]

MIN_HOLES = 4  # a dark region enclosing fewer bright blobs is not worth a closer look
DARK_FRACTION = 0.3  # board pixels: below this fraction of the way from black to bright
GROW = "grow"  # BoardFitter.fit's answer when the board touches the region's edge


class BoardFit(NamedTuple):
    """A board found in a region of interest, in image pixels."""

    landmark_id: int
    image_points: np.ndarray  # (N, 2) square centres, in the order of lit_cells(landmark_id)
    plane_points: np.ndarray  # (N, 2) their landmark-plane centres, metres
    homography: np.ndarray  # 3x3, landmark plane (m) -> image (px)
    reprojection_rms: float  # px


class _Board(NamedTuple):
    """The board's dark region, cut to its bounding box."""

    origin: np.ndarray  # (2,) the box's top-left pixel in the image
    grey: np.ndarray  # the image's pixels in the box (a view)
    dark: np.ndarray  # uint8, 1 on the board's dark pixels
    bright: np.ndarray  # uint8, 1 where brighter than the board threshold
    outline: np.ndarray  # (K, 2) int32 convex hull of the dark region, box pixels


class _Squares(NamedTuple):
    """The white squares inside the board's outline, in box pixels."""

    boxes: np.ndarray  # (N, 4) bounding boxes of the blobs: x, y, width, height
    centres: np.ndarray  # (N, 2) blob centroids
    hull: np.ndarray  # uint8, 1 inside the convex hull of the board's dark region


def apply_homography(h: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Points (..., 2) mapped through the 3x3 homography ``h``."""
    xy = np.asarray(xy, dtype=np.float64)
    return cv2.perspectiveTransform(xy.reshape(-1, 1, 2), h).reshape(xy.shape)


class BoardFitter:
    """Fits the board of ``pattern`` in regions of interest (see the module docstring).

    ``max_reprojection_px`` bounds the RMS distance of the square centres from the fitted
    homography (also at most 0.1 of the square pitch in pixels); ids outside ``valid_ids``
    (when given) are rejected as misreads. When ``trace`` is a list, each rejection appends
    its reason.
    """

    def __init__(
        self,
        pattern: LandmarkPattern,
        max_reprojection_px: float,
        valid_ids: set[int] | None = None,
    ) -> None:
        self.pattern = pattern
        self.max_reprojection_px = float(max_reprojection_px)
        self.valid_ids = None if valid_ids is None else {int(i) for i in valid_ids}
        self.trace: list[str] | None = None
        g, centre = pattern.grid, pattern.grid // 2
        rows, cols = np.divmod(np.arange(g * g), g)
        # Cells of the grid, row-major: plane coordinates of their centres, whether they are
        # always lit (ring and centre) and the id bit they carry.
        self._cell_xy = np.array(
            [cell_centre(r, c, pattern) for r, c in zip(rows, cols, strict=True)]
        )
        ring = (rows == 0) | (rows == g - 1) | (cols == 0) | (cols == g - 1)
        self._required = ring | ((rows == centre) & (cols == centre))
        self._min_squares = int(np.count_nonzero(self._required))
        cells = np.arange(g * g).reshape(g, g)
        across = np.stack([cells[:, :-1].ravel(), cells[:, 1:].ravel()])
        down = np.stack([cells[:-1].ravel(), cells[1:].ravel()])
        self._neighbours = np.hstack([across, down])  # (2, M) side-by-side cells, for the pitch
        self._bit_value = np.zeros(g * g, dtype=np.int64)
        for bit, (r, c) in enumerate(pattern.id_cells):
            self._bit_value[r * g + c] = 1 << bit
        half = (g - 1) / 2 * pattern.pitch
        # Corner squares of the ring: top-left, top-right, bottom-right, bottom-left.
        self._corner_xy = np.float32([[-half, half], [half, half], [half, -half], [-half, -half]])
        self.board_xy = board_corners(pattern)

    def fit(self, grey: np.ndarray, x0: int, y0: int, x1: int, y1: int) -> BoardFit | str | None:
        """The board in the region ``grey[y0:y1, x0:x1]``, :data:`GROW` if it touches an edge
        of the region inside the frame, or None when there is none."""
        board = self._find_board(grey, x0, y0, x1, y1)
        if board is None or board is GROW:
            return board
        squares = self._find_squares(board)
        if squares is None:
            return None
        grid = self._assign_cells(squares.centres)
        if grid is None:
            return None
        cell, pitch_px = grid
        landmark_id = int(self._bit_value[cell].sum())
        if self.valid_ids is not None and landmark_id not in self.valid_ids:
            return self._fail("id not valid")
        order = np.argsort(cell)  # lit_cells order is row-major, as the cell numbers
        squares = squares._replace(boxes=squares.boxes[order], centres=squares.centres[order])
        cell = cell[order]
        pts = self._square_centres(board, squares, pitch_px) + board.origin
        plane = self._cell_xy[cell]
        fit = self._fit_homography(plane, pts, pitch_px)
        if fit is None:
            return None
        return BoardFit(landmark_id, pts, plane, *fit)

    def _find_board(
        self, grey: np.ndarray, x0: int, y0: int, x1: int, y1: int
    ) -> _Board | str | None:
        """The board's dark region (a ``_Board``), :data:`GROW` or None.

        A black board on a lighter wall is the darkest thing around: the threshold is 30 %
        of the way from the region's black level to its bright level.
        """
        roi = grey[y0:y1, x0:x1]
        rh, rw = roi.shape
        sample = roi[:: max(1, rh // 24), :: max(1, rw // 24)].ravel()
        k1, k90 = len(sample) // 100, (9 * len(sample)) // 10
        lo, hi = np.partition(sample, (k1, k90))[[k1, k90]].tolist()
        if hi - lo < 30:
            return self._fail("flat region")
        threshold = lo + DARK_FRACTION * (hi - lo)
        dark = cv2.threshold(roi, threshold, 1, cv2.THRESH_BINARY_INV)[1]
        contours, hierarchy = cv2.findContours(dark, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_SIMPLE)
        parent = hierarchy[0, :, 3] if hierarchy is not None else np.empty(0, np.int32)
        holes = parent[parent >= 0]  # each hole names the dark region around it
        counts = np.bincount(holes) if len(holes) >= MIN_HOLES else np.zeros(1, np.int64)
        k = int(counts.argmax())
        if counts[k] < MIN_HOLES:
            return self._fail("no dark region with squares")
        x, y, w, h = cv2.boundingRect(contours[k])
        touches = (x == 0, y == 0, x + w >= rw, y + h >= rh)  # left, top, right, bottom
        if any(touches):
            # The board is wholly inside the frame: growing past the frame's edge cannot help.
            frame = (x0 == 0, y0 == 0, x1 == grey.shape[1], y1 == grey.shape[0])
            if any(t and f for t, f in zip(touches, frame, strict=True)):
                return self._fail("dark region reaches the frame's edge")
            return GROW
        box, inside = np.s_[y : y + h, x : x + w], np.zeros((h, w), np.uint8)
        cv2.drawContours(inside, contours, k, 1, cv2.FILLED, offset=(-x, -y))
        outline = cv2.convexHull(contours[k]).reshape(-1, 2) - np.int32([x, y])
        origin = np.array([x0 + x, y0 + y], dtype=np.float64)
        return _Board(origin, roi[box], inside & dark[box], 1 - dark[box], outline)

    def _find_squares(self, board: _Board) -> _Squares | None:
        """The bright blobs inside the board's convex hull shrunk by a pixel, so that slivers
        of wall cut by the hull's slanted edges are left out."""
        inside = np.zeros_like(board.dark)
        cv2.fillConvexPoly(inside, _shrink(board.outline, 1.0), 1)
        inside &= board.bright
        n_blobs, _, stats, centres = cv2.connectedComponentsWithStats(inside, connectivity=4)
        area = stats[1:, 4]
        # Slivers of wall where the hull's edge cuts a pixel are far smaller than a square.
        sel = np.flatnonzero(area >= 0.3 * _median(area)) if n_blobs > 1 else np.arange(0)
        if len(sel) < self._min_squares:
            return self._fail("too few squares")
        if len(sel) > len(self._cell_xy):
            return self._fail("too many squares")
        hull = np.zeros_like(board.dark)
        cv2.fillConvexPoly(hull, board.outline, 1)
        return _Squares(stats[1:, :4][sel], centres[1:][sel], hull)

    def _assign_cells(self, pts: np.ndarray) -> tuple[np.ndarray, float] | None:
        """Grid cell of each square centre ``pts`` and the smallest cell pitch in pixels.

        The ring's corner squares, extreme along the image diagonals, give a first homography
        that predicts each cell's centre; every square must be near one, all ring cells and
        the centre must be present and no cell may be used twice.
        """
        s, d = pts[:, 0] + pts[:, 1], pts[:, 0] - pts[:, 1]
        corners = [int(s.argmin()), int(d.argmax()), int(s.argmax()), int(d.argmin())]
        if len(set(corners)) < 4:
            return self._fail("corner squares not distinct")
        h0 = cv2.getPerspectiveTransform(self._corner_xy, pts[corners].astype(np.float32))
        pred = apply_homography(h0, self._cell_xy)
        if not np.isfinite(pred).all():
            return self._fail("degenerate homography")
        step = pred[self._neighbours[0]] - pred[self._neighbours[1]]
        pitch_px = math.sqrt(float((step * step).sum(axis=1).min()))
        dist2 = ((pts[:, None, :] - pred[None, :, :]) ** 2).sum(axis=2)
        cell = dist2.argmin(axis=1)
        if dist2.min(axis=1).max() > (0.35 * pitch_px) ** 2:
            return self._fail("blob off the grid")
        used = np.bincount(cell, minlength=len(pred))
        if used.max() > 1 or (self._required & (used == 0)).any():
            return self._fail("ring incomplete or cell reused")
        return cell, pitch_px

    def _square_centres(self, board: _Board, squares: _Squares, pitch_px: float) -> np.ndarray:
        """Sub-pixel square centres (box pixels): intensity-weighted centroids above the
        board's black level.

        Each square's window is its blob's box grown by 40 % of the gap between squares (1 to
        4 pixels); only pixels inside the board's hull count.
        """
        gap_px = pitch_px * (1.0 - self.pattern.square_size / self.pattern.pitch)
        margin = min(max(round(0.4 * gap_px), 1), 4)
        # Black level: the median of the board's dark pixels on a grid of about 1000 pixels.
        step = max(1, round(math.sqrt(board.dark.size / 1024)))
        dark = board.grey[::step, ::step][board.dark[::step, ::step].view(bool)]
        black = _median(dark) if len(dark) else 0.0
        # Bright level: grey at the blob centres (interpolated: 2 px blobs centre between pixels)
        at_centres = squares.centres.astype(np.float32)[:, None, :]
        peak = _median(cv2.remap(board.grey, at_centres, None, cv2.INTER_LINEAR).ravel())
        floor = black + max(0.15 * (peak - black), 4.0)
        weight = np.maximum(board.grey - np.float32(floor), 0.0, dtype=np.float32)
        weight *= squares.hull
        return _window_centroids(weight, squares.boxes, margin, fallback=squares.centres)

    def _fit_homography(
        self, plane: np.ndarray, pts: np.ndarray, pitch_px: float
    ) -> tuple[np.ndarray, float] | None:
        """Least-squares homography plane -> image and its RMS error, unless that is too large."""
        hom, _ = cv2.findHomography(plane, pts, 0)
        if hom is None:
            return self._fail("homography fit failed")
        dx, dy = (apply_homography(hom, plane) - pts).T
        resid2 = dx * dx + dy * dy
        rms = math.sqrt(float(resid2.sum()) / len(resid2))
        if (
            rms > min(self.max_reprojection_px, 0.1 * pitch_px)
            or math.sqrt(float(resid2.max())) > 3 * max(rms, 0.2) + 0.1 * pitch_px
        ):
            return self._fail("reprojection error")
        return hom, rms

    def _fail(self, reason: str) -> None:
        if self.trace is not None:
            self.trace.append(reason)


def _window_centroids(
    weight: np.ndarray, boxes: np.ndarray, margin: int, fallback: np.ndarray
) -> np.ndarray:
    """Centroids of ``weight`` over each box (N, 4: x, y, w, h) grown by ``margin`` pixels.

    One integral image of the weight and its x and y moments gives every window's sums from
    its four corners. Windows with no weight get their ``fallback`` point.
    """
    h, w = weight.shape
    xs = np.arange(w, dtype=np.float32)
    ys = np.arange(h, dtype=np.float32)[:, None]
    table = cv2.integral(cv2.merge([weight, weight * xs, weight * ys]), sdepth=cv2.CV_64F)
    x0, y0 = np.maximum(boxes[:, :2] - margin, 0).T
    x1, y1 = np.minimum(boxes[:, :2] + boxes[:, 2:4] + margin, (w, h)).T
    sums = table[y1, x1] - table[y0, x1] - table[y1, x0] + table[y0, x0]  # (N, 3)
    total = sums[:, 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        out = sums[:, 1:] / total[:, None]
    bad = ~(total > 0)
    out[bad] = fallback[bad]
    return out


def _median(values: np.ndarray) -> float:
    """Median of a 1-D array (as ``np.median``, without its overhead on small arrays)."""
    k = len(values) // 2
    if len(values) % 2:
        return float(np.partition(values, k)[k])
    part = np.partition(values, (k - 1, k))
    return 0.5 * (float(part[k - 1]) + float(part[k]))


def _shrink(polygon: np.ndarray, by: float) -> np.ndarray:
    """Convex polygon (K, 2) pulled towards its centroid by about ``by`` pixels (int32)."""
    p = polygon.astype(np.float64)
    c = p.sum(axis=0) / len(p)
    r = np.hypot(*(p - c).T)[:, None]
    q = c + (p - c) * np.maximum(1.0 - by / np.maximum(r, 1e-9), 0.0)
    return np.floor(q + 0.5).astype(np.int32)
