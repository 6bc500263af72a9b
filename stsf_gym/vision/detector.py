"""Landmark detector of the paper's sect. 3.1: template matching, then sub-pixel square centres.

The detector runs in two stages.

1. **Candidates by template matching** (paper eq. 6-7): local maxima of the normalised
   cross-correlation with a blurred board template over an image pyramid, see
   :mod:`stsf_gym.vision.template`.

2. **Geometry** on the full-resolution image around each candidate: the board is the dark
   connected region enclosing the most bright holes; the white squares are the bright blobs
   inside its convex hull (far away the black border can be thinner than a pixel, so outer
   squares are not always holes). The four corner squares of the always-lit outer ring
   (extreme along the image diagonals) give a first homography from the landmark plane,
   which assigns every blob to a grid cell; all ring cells and the centre must be present,
   no blob may be left over, and the lit inner cells give the id
   (:func:`~stsf_gym.vision.landmarks.decode_landmark_id`). Each square's centre is then the
   intensity-weighted centroid (above the board's black level) of a window around its blob,
   a homography is fitted to all squares by least squares, and the candidate is rejected
   when its reprojection error is too large.

Assumptions: the board is seen from its front, with image roll under 45 degrees (the ring
and centre are symmetric under 90 degree turns, so "up" is taken from the image), whole
inside the frame and at least about ``min_board_px`` pixels wide. Pixel coordinates have
pixel centres at integers (the convention of ``env.unwrapped.camera_matrix``).

This module does not import PyBullet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import cv2
import numpy as np

from stsf_gym.vision.landmarks import (
    LandmarkPattern,
    board_corners,
    cell_centre,
    decode_landmark_id,
    lit_cells,
)
from stsf_gym.vision.template import Candidate, TemplateMatcher

__all__ = ["Detection", "LandmarkDetector"]

MIN_HOLES = 4  # a dark region enclosing fewer bright blobs is not worth a closer look
DARK_FRACTION = 0.3  # board pixels: below this fraction of the way from black to bright


@dataclass(frozen=True)
class Detection:
    """One landmark found in an image.

    ``image_points[k]`` (pixels, x right, y down, pixel centres at integers) is the measured
    centre of the white square whose landmark-plane centre is ``plane_points[k]`` (metres,
    x right, y up) and which is row ``indices[k]`` of
    :func:`stsf_gym.vision.landmarks.square_centres` for ``landmark_id``; every lit square
    of the landmark is present, in that order.
    """

    landmark_id: int
    image_points: np.ndarray  # (N, 2) float64 pixels
    plane_points: np.ndarray  # (N, 2) float64 metres in the landmark plane
    indices: np.ndarray  # (N,) int64 rows of square_centres(landmark_id, pattern)
    score: float  # NCC (eq. 7, normalised) of the candidate that led to this detection
    homography: np.ndarray = field(repr=False)  # 3x3, landmark plane (m) -> image (px)
    reprojection_rms: float = 0.0  # px, image_points vs homography @ plane_points
    corners: np.ndarray = field(default=None, repr=False)  # (4, 2) board corners in pixels

    def project(self, plane_xy: np.ndarray) -> np.ndarray:
        """Pixels of landmark-plane points (..., 2) through the fitted homography."""
        return _apply_homography(self.homography, np.asarray(plane_xy, dtype=np.float64))


class _Board(NamedTuple):
    """The board's dark region in a region of interest."""

    dark: np.ndarray  # uint8, 1 where darker than the board threshold
    labels: np.ndarray  # 8-connected components of ``dark``
    label: int  # the board's component
    box: np.ndarray  # its bounding box: x, y, width, height


class _Squares(NamedTuple):
    """The white squares inside the board's outline."""

    hull_mask: np.ndarray  # uint8, 1 inside the convex hull of the board's dark region
    boxes: np.ndarray  # (N, 4) bounding boxes of the blobs: x, y, width, height
    centres: np.ndarray  # (N, 2) blob centroids, pixels


def _apply_homography(h: np.ndarray, xy: np.ndarray) -> np.ndarray:
    xy = np.asarray(xy, dtype=np.float64)
    p = xy @ h[:, :2].T + h[:, 2]
    return p[..., :2] / p[..., 2:3]


def _to_grey(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.dtype != np.uint8:
        raise TypeError(f"image must be uint8, got {image.dtype}")
    if image.ndim == 2:
        return image
    if image.ndim == 3 and image.shape[2] == 1:
        return image[:, :, 0]
    if image.ndim == 3 and image.shape[2] in (3, 4):
        code = cv2.COLOR_RGB2GRAY if image.shape[2] == 3 else cv2.COLOR_RGBA2GRAY
        return cv2.cvtColor(image, code)
    raise ValueError(f"image must be HxW grey or HxWx3 RGB, got shape {image.shape}")


class LandmarkDetector:
    """Find the paper's Fig. 3 landmarks in an image (see the module docstring).

    Parameters
    ----------
    pattern:
        Board geometry (must match the landmarks in the world).
    ncc_threshold:
        Minimum normalised cross-correlation (eq. 7) of a candidate region.
    min_board_px, max_board_px:
        Range of board sides (full-resolution pixels) searched; ``max_board_px`` defaults
        to the image's shorter side. Smaller ``min_board_px`` costs more time.
    template_px:
        Side of the smallest template (pixels at its pyramid level); the image is first
        shrunk by ``min_board_px / template_px``.
    max_candidates:
        At most this many candidate regions (best NCC first) are checked per frame.
    max_reprojection_px:
        Reject a board whose square centres are further than this (RMS, pixels) from the
        least-squares homography; also at most ``0.1`` of the square pitch in pixels.
    valid_ids:
        If given, only these ids are accepted (others are treated as misreads).
    """

    def __init__(
        self,
        pattern: LandmarkPattern | None = None,
        *,
        ncc_threshold: float = 0.55,
        min_board_px: float = 18.0,
        max_board_px: float | None = None,
        template_px: int = 8,
        max_candidates: int = 8,
        max_reprojection_px: float = 1.0,
        valid_ids: set[int] | None = None,
    ) -> None:
        self.pattern = pattern or LandmarkPattern()
        self.matcher = TemplateMatcher(
            self.pattern,
            ncc_threshold=ncc_threshold,
            min_board_px=min_board_px,
            max_board_px=max_board_px,
            template_px=template_px,
            max_peaks=4 * int(max_candidates),
        )
        self.max_candidates = int(max_candidates)
        self.max_reprojection_px = float(max_reprojection_px)
        self.valid_ids = None if valid_ids is None else {int(i) for i in valid_ids}
        p = self.pattern
        g = p.grid
        centre = g // 2
        # Cells of the grid, row-major; plane coordinates of their centres.
        self._cells = [(r, c) for r in range(g) for c in range(g)]
        self._cell_xy = np.array([cell_centre(r, c, p) for r, c in self._cells])
        self._required = np.array(
            [
                r in (0, g - 1) or c in (0, g - 1) or (r, c) == (centre, centre)
                for r, c in self._cells
            ]
        )
        half = (g - 1) / 2 * p.pitch
        # Corner squares of the ring: top-left, top-right, bottom-right, bottom-left.
        self._corner_xy = np.array([[-half, half], [half, half], [half, -half], [-half, -half]])
        self._board_xy = board_corners(p)
        self._lit_index_cache: dict[int, dict[tuple[int, int], int]] = {}
        self._trace: list[str] | None = None  # rejection reasons, when debugging

    @property
    def ncc_threshold(self) -> float:
        """Minimum NCC of a candidate region."""
        return self.matcher.ncc_threshold

    @property
    def min_board_px(self) -> float:
        """Smallest board side searched, pixels."""
        return self.matcher.min_board_px

    @property
    def max_board_px(self) -> float | None:
        """Largest board side searched, pixels (None: the image's shorter side)."""
        return self.matcher.max_board_px

    @property
    def template_px(self) -> int:
        """Side of the smallest template, pixels at its pyramid level."""
        return self.matcher.template_px

    def candidates(self, grey: np.ndarray) -> list[Candidate]:
        """Candidate board regions of stage 1 (eq. 6-7) in a uint8 grey image, best first."""
        return self.matcher.candidates(grey)

    def detect(self, image: np.ndarray) -> list[Detection]:
        """Landmarks in ``image`` (HxW grey or HxWx3 RGB, uint8), best NCC score first."""
        grey = _to_grey(image)
        detections: list[Detection] = []
        tried = 0
        for cand in self.candidates(grey):
            if tried >= self.max_candidates:
                break
            if any(_inside(d.corners, cand.cx, cand.cy) for d in detections):
                continue
            tried += 1
            det = self._verify(grey, cand)
            if det is None:
                continue
            centre = det.project(np.zeros(2))
            if any(_inside(d.corners, *centre) for d in detections):
                continue
            detections.append(det)
        return detections

    def _verify(self, grey: np.ndarray, cand: Candidate) -> Detection | None:
        """The landmark around a candidate, growing the region while the board touches its edge."""
        h, w = grey.shape
        half = 0.9 * cand.size + 2
        for _ in range(3):
            x0, y0 = max(0, math.floor(cand.cx - half)), max(0, math.floor(cand.cy - half))
            x1, y1 = min(w, math.ceil(cand.cx + half) + 1), min(h, math.ceil(cand.cy + half) + 1)
            if x1 - x0 < 8 or y1 - y0 < 8:
                return None
            result = self._fit_roi(grey[y0:y1, x0:x1], cand.score)
            if result == "grow":
                if x0 == 0 and y0 == 0 and x1 == w and y1 == h:
                    return None
                half *= 1.7
                continue
            if result is None:
                return None
            return _shift(result, x0, y0)
        return None

    def _fit_roi(self, roi: np.ndarray, score: float) -> Detection | str | None:
        """Find the board in a region of interest; coordinates relative to the region.

        Returns ``"grow"`` when the board touches the region's edge, None when rejected.
        """
        board = self._find_board(roi)
        if board is None:
            return None
        dx, dy, dw, dh = board.box
        if dx == 0 or dy == 0 or dx + dw >= roi.shape[1] or dy + dh >= roi.shape[0]:
            return "grow"
        squares = self._find_squares(board)
        if squares is None:
            return None
        grid = self._assign_cells(squares.centres)
        if grid is None:
            return None
        cell, pitch_px = grid
        landmark_id = decode_landmark_id({self._cells[i] for i in cell.tolist()}, self.pattern)
        if self.valid_ids is not None and landmark_id not in self.valid_ids:
            return self._fail("id not valid")
        index_of = self._lit_index(landmark_id)
        indices = np.array([index_of[self._cells[i]] for i in cell.tolist()], dtype=np.int64)
        order = np.argsort(indices)
        squares = squares._replace(boxes=squares.boxes[order], centres=squares.centres[order])
        plane = self._cell_xy[cell[order]]
        pts = self._square_centres(roi, board, squares, pitch_px)
        fit = self._fit_homography(plane, pts, pitch_px)
        if fit is None:
            return None
        hom, rms = fit
        return Detection(
            landmark_id=landmark_id,
            image_points=pts,
            plane_points=plane,
            indices=indices[order],
            score=score,
            homography=hom,
            reprojection_rms=rms,
            corners=_apply_homography(hom, self._board_xy),
        )

    def _find_board(self, roi: np.ndarray) -> _Board | None:
        """The board's dark region; a black board on a lighter wall is the darkest thing around."""
        rh, rw = roi.shape
        # Black level of the board and bright level of squares and wall.
        sample = roi[:: max(1, rh // 24), :: max(1, rw // 24)].ravel()
        k1, k90 = len(sample) // 100, (9 * len(sample)) // 10
        lo, hi = (float(v) for v in np.partition(sample, (k1, k90))[[k1, k90]])
        if hi - lo < 30:
            return self._fail("flat region")
        dark = (roi <= lo + DARK_FRACTION * (hi - lo)).astype(np.uint8)
        n_d, labels, stats, _ = cv2.connectedComponentsWithStats(dark, connectivity=8)
        if n_d < 2:
            return self._fail("no dark region")
        label, holes = self._board_label(dark, labels, n_d)
        if holes < MIN_HOLES:
            return self._fail("no dark region with squares")
        return _Board(dark, labels, label, stats[label, :4])

    @staticmethod
    def _board_label(dark: np.ndarray, labels: np.ndarray, n_labels: int) -> tuple[int, int]:
        """The board's dark region: the label enclosing most bright blobs, and their count."""
        rh, rw = dark.shape
        _, _, st_b, cen_b = cv2.connectedComponentsWithStats(1 - dark, connectivity=4)
        bx, by, bw, bh = (st_b[1:, i] for i in range(4))
        interior = (bx > 0) & (by > 0) & (bx + bw < rw) & (by + bh < rh)
        if not np.any(interior):
            return 0, 0
        row = np.clip(np.rint(cen_b[1:, 1]).astype(int), 0, rh - 1)
        enclosing = labels[row[interior], np.maximum(bx[interior] - 1, 0)]
        counts = np.bincount(enclosing, minlength=n_labels)
        counts[0] = 0
        board = int(np.argmax(counts))
        return board, int(counts[board])

    def _find_squares(self, board: _Board) -> _Squares | None:
        """White squares: the bright blobs inside the convex hull of the board's dark region.

        Far away the black border can be thinner than a pixel, so the outer squares are not
        always holes of the dark region.
        """
        dx, dy, dw, dh = board.box
        mask = (board.labels[dy : dy + dh, dx : dx + dw] == board.label).astype(np.uint8)
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        hull = cv2.convexHull(np.concatenate(contours) + np.array([dx, dy], np.int32))
        hull_mask = np.zeros_like(board.dark)
        cv2.fillConvexPoly(hull_mask, hull, 1)
        # Bright pixels inside the hull shrunk by a pixel, so that slivers of wall cut by the
        # hull's slanted edges are left out.
        inside = np.zeros_like(board.dark)
        cv2.fillConvexPoly(inside, _shrink(hull.reshape(-1, 2), 1.0), 1)
        inside &= 1 - board.dark
        n_b, _, stats, centres = cv2.connectedComponentsWithStats(inside, connectivity=4)
        area = stats[1:, 4]
        # Slivers of wall where the hull's edge cuts a pixel are far smaller than a square.
        sel = np.nonzero(area >= 0.3 * np.median(area))[0] if n_b > 1 else np.arange(0)
        if len(sel) < int(self._required.sum()):
            return self._fail("too few squares")
        if len(sel) > len(self._cells):
            return self._fail("too many squares")
        return _Squares(hull_mask, stats[1:, :4][sel], centres[1:][sel])

    def _assign_cells(self, pts: np.ndarray) -> tuple[np.ndarray, float] | None:
        """Grid cell of each square centre ``pts`` and the smallest cell pitch in pixels.

        The ring's corner squares, extreme along the image diagonals, give a first homography
        that predicts each cell's centre; every square must be near one, all ring cells and
        the centre must be present and no cell may be used twice.
        """
        s, d = pts[:, 0] + pts[:, 1], pts[:, 0] - pts[:, 1]
        corner_idx = [int(np.argmin(s)), int(np.argmax(d)), int(np.argmax(s)), int(np.argmin(d))]
        if len(set(corner_idx)) < 4:
            return self._fail("corner squares not distinct")
        h0 = cv2.getPerspectiveTransform(
            self._corner_xy.astype(np.float32), pts[corner_idx].astype(np.float32)
        )
        pred = _apply_homography(h0, self._cell_xy)
        if not np.all(np.isfinite(pred)):
            return self._fail("degenerate homography")
        pitch_px = self._min_pitch(pred)
        dist2 = ((pts[:, None, :] - pred[None, :, :]) ** 2).sum(axis=2)
        cell = np.argmin(dist2, axis=1)
        if np.any(dist2[np.arange(len(pts)), cell] > (0.35 * pitch_px) ** 2):
            return self._fail("blob off the grid")
        if len(np.unique(cell)) != len(cell) or not np.all(
            np.isin(np.nonzero(self._required)[0], cell)
        ):
            return self._fail("ring incomplete or cell reused")
        return cell, pitch_px

    def _square_centres(
        self, roi: np.ndarray, board: _Board, squares: _Squares, pitch_px: float
    ) -> np.ndarray:
        """Sub-pixel square centres: intensity-weighted centroids above the board's black."""
        gap_px = pitch_px * (1.0 - self.pattern.square_size / self.pattern.pitch)
        margin = int(np.clip(round(0.4 * gap_px), 1, 4))
        vals = roi[board.labels == board.label]
        black = float(np.median(vals[:: max(1, len(vals) // 512)])) if len(vals) else 0.0
        ci = np.rint(squares.centres).astype(int)
        peak = float(np.median(roi[ci[:, 1], ci[:, 0]]))
        floor = black + max(0.15 * (peak - black), 4.0)
        return _weighted_centroids(
            roi, squares.hull_mask, squares.boxes, margin, floor, fallback=squares.centres
        )

    def _fit_homography(
        self, plane: np.ndarray, pts: np.ndarray, pitch_px: float
    ) -> tuple[np.ndarray, float] | None:
        """Least-squares homography plane -> image and its RMS error, unless that is too large."""
        hom, _ = cv2.findHomography(plane, pts, 0)
        if hom is None:
            return self._fail("homography fit failed")
        resid = np.linalg.norm(_apply_homography(hom, plane) - pts, axis=1)
        rms = float(np.sqrt(np.mean(resid**2)))
        if (
            rms > min(self.max_reprojection_px, 0.1 * pitch_px)
            or resid.max() > 3 * max(rms, 0.2) + 0.1 * pitch_px
        ):
            return self._fail("reprojection error")
        return hom, rms

    def _fail(self, reason: str) -> None:
        if self._trace is not None:
            self._trace.append(reason)

    def _min_pitch(self, pred: np.ndarray) -> float:
        g = self.pattern.grid
        grid = pred.reshape(g, g, 2)
        dx = np.linalg.norm(np.diff(grid, axis=1), axis=2).min()
        dy = np.linalg.norm(np.diff(grid, axis=0), axis=2).min()
        return float(min(dx, dy))

    def _lit_index(self, landmark_id: int) -> dict[tuple[int, int], int]:
        if landmark_id not in self._lit_index_cache:
            cells = lit_cells(landmark_id, self.pattern)
            self._lit_index_cache[landmark_id] = {c: i for i, c in enumerate(cells)}
        return self._lit_index_cache[landmark_id]


def _weighted_centroids(
    roi: np.ndarray,
    mask: np.ndarray,
    boxes: np.ndarray,
    margin: int,
    floor: float,
    fallback: np.ndarray,
) -> np.ndarray:
    """Centroids of ``max(I - floor, 0)`` over each blob's box grown by ``margin`` pixels.

    Only pixels where ``mask`` is set (the board) count; all blobs at once (vectorised).
    """
    rh, rw = roi.shape
    x0 = np.maximum(boxes[:, 0] - margin, 0)
    y0 = np.maximum(boxes[:, 1] - margin, 0)
    x1 = np.minimum(boxes[:, 0] + boxes[:, 2] + margin, rw)
    y1 = np.minimum(boxes[:, 1] + boxes[:, 3] + margin, rh)
    ww, hh = int((x1 - x0).max()), int((y1 - y0).max())
    oy, ox = np.mgrid[0:hh, 0:ww]
    ys = y0[:, None, None] + oy[None]
    xs = x0[:, None, None] + ox[None]
    inside = (ys < y1[:, None, None]) & (xs < x1[:, None, None])
    yc, xc = np.minimum(ys, rh - 1), np.minimum(xs, rw - 1)
    vals = roi[yc, xc].astype(np.float64)
    wgt = np.where(inside & (mask[yc, xc] > 0), np.maximum(vals - floor, 0.0), 0.0)
    total = wgt.sum(axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        cx = (wgt * xs).sum(axis=(1, 2)) / total
        cy = (wgt * ys).sum(axis=(1, 2)) / total
    out = np.stack([cx, cy], axis=1)
    bad = ~(total > 0)
    out[bad] = fallback[bad]
    return out


def _shrink(polygon: np.ndarray, by: float) -> np.ndarray:
    """Convex polygon (K, 2) pulled towards its centroid by about ``by`` pixels (int32)."""
    p = polygon.astype(np.float64)
    c = p.mean(axis=0)
    r = np.linalg.norm(p - c, axis=1, keepdims=True)
    q = c + (p - c) * np.clip(1.0 - by / np.maximum(r, 1e-9), 0.0, 1.0)
    return np.rint(q).astype(np.int32)


def _inside(corners: np.ndarray, x: float, y: float) -> bool:
    if corners is None:
        return False
    return cv2.pointPolygonTest(corners.astype(np.float32), (float(x), float(y)), False) >= 0


def _shift(det: Detection, x0: int, y0: int) -> Detection:
    t = np.array([[1.0, 0.0, x0], [0.0, 1.0, y0], [0.0, 0.0, 1.0]])
    offset = np.array([x0, y0], dtype=np.float64)
    return Detection(
        landmark_id=det.landmark_id,
        image_points=det.image_points + offset,
        plane_points=det.plane_points,
        indices=det.indices,
        score=det.score,
        homography=t @ det.homography,
        reprojection_rms=det.reprojection_rms,
        corners=det.corners + offset,
    )
