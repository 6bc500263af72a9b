"""Track-aided matching: a board searched where a landmark track says it must be.

The plain detector (:mod:`stsf_gym.vision.detector`) knows nothing of the past: it searches the
whole frame for boards at least ``min_board_px`` wide and must read each one's id from blobs it
can separate. A landmark *track* knows more: which board it follows and, carried by odometry,
where that board must appear in this frame and how large (a :class:`BoardPrediction`). The
search then needs far less evidence, the paper's eq. 6-7 template matching with a lower
threshold at one place and one size:

1. the board of the predicted id is drawn at its predicted place (the exact area-sampled
   pattern, through the homography of the predicted corners) and slid over the search window
   (normalised cross-correlation, eq. 7), for the error of the prediction's position;
2. the homography is refined by direct alignment (OpenCV's ECC, the correlation coefficient
   maximised over the eight homography parameters), masked to the board;
3. the match is kept only if its correlation reaches ``min_correlation``, it moved by no more
   than the search radius, and the cells of the refined board read back the predicted id
   (every always-lit cell brighter, every id cell on the right side of the midpoint between
   the board's black and white levels): a board of another id is never taken for this one.

The square centres are the refined homography's images of their plane centres. So boards too
small (far), too foreshortened (oblique) or too blurred for the blob reading still match, down
to about ``min_board_px`` of this module (10 px, a 2 px square pitch). This module does not
import PyBullet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from stsf_gym.vision.board import apply_homography
from stsf_gym.vision.detector import Detection
from stsf_gym.vision.landmarks import (
    LandmarkPattern,
    board_corners,
    cell_centre,
    landmark_image,
    lit_cells,
    square_centres,
)

SUPERSAMPLE = 4  # samples per pixel and axis when the predicted board is drawn
ECC_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 60, 1e-4)


@dataclass(frozen=True)
class BoardPrediction:
    """Where a track expects landmark ``landmark_id``: its board's four corners in pixels
    (:func:`~stsf_gym.vision.landmarks.board_corners` order) and the radius (px) within
    which its position may be off."""

    landmark_id: int
    corners: np.ndarray
    search_px: float

    @property
    def size_px(self) -> float:
        """The shorter of the predicted board's mean width and height (pixels)."""
        sides = np.linalg.norm(self.corners - self.corners[[1, 2, 3, 0]], axis=1)
        return float(min(sides[0] + sides[2], sides[1] + sides[3]) / 2)


class PredictedMatcher:
    """``matcher.match(grey, prediction) -> Detection | None`` (see the module docstring)."""

    def __init__(
        self,
        pattern: LandmarkPattern,
        min_correlation: float = 0.6,
        min_board_px: float = 10.0,
        min_contrast: float = 12.0,
    ) -> None:
        self.pattern = pattern
        self.min_correlation, self.min_board_px = float(min_correlation), float(min_board_px)
        self.min_contrast = float(min_contrast)
        self.plane_corners = board_corners(pattern)
        self._textures: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        g = pattern.grid
        self._cells = np.array([cell_centre(r, c, pattern) for r in range(g) for c in range(g)])
        ring = pattern.size / 2 - pattern.border / 2  # the black border's middle line
        t = np.linspace(-1, 1, 5)[:-1] * ring
        self._border = np.concatenate(
            [np.column_stack([t, np.full(4, ring)]), np.column_stack([np.full(4, ring), -t])]
        )
        self._border = np.concatenate([self._border, -self._border])

    def match(self, grey: np.ndarray, prediction: BoardPrediction) -> Detection | None:
        """The predicted board in the uint8 grey image, or None when it is not there."""
        if prediction.size_px < self.min_board_px or not np.isfinite(prediction.corners).all():
            return None
        h_pred = cv2.getPerspectiveTransform(
            self.plane_corners.astype(np.float32), prediction.corners.astype(np.float32)
        )
        radius = math.ceil(prediction.search_px)
        pad = radius + 2
        lo = np.floor(prediction.corners.min(axis=0)).astype(int) - pad
        hi = np.ceil(prediction.corners.max(axis=0)).astype(int) + pad + 1
        if (lo < 0).any() or (hi > grey.shape[::-1]).any():
            return None  # the board must lie wholly inside the frame
        window = grey[lo[1] : hi[1], lo[0] : hi[0]].astype(np.float32)
        # the board drawn where predicted, in the coordinates of the window's centre part
        inner = np.array([radius, radius])
        shape = (hi - lo - 2 * radius)[::-1]
        to_inner = _translation(-(lo + inner)) @ h_pred
        template, mask = self._draw(prediction.landmark_id, to_inner, shape)
        if mask.sum() < 16:
            return None
        shift = _best_shift(window, template, mask)
        if shift is None:
            return None
        # the board drawn at its best placement over the whole window, then the window aligned
        # to it (ECC; the window is the template so the board's mask applies to the drawing)
        placed = _translation(shift) @ to_inner
        model, model_mask = self._draw(prediction.landmark_id, placed, window.shape)
        warp = np.eye(3, dtype=np.float32)
        try:
            rho, warp = cv2.findTransformECC(
                window, model, warp, cv2.MOTION_HOMOGRAPHY, ECC_CRITERIA, model_mask, 1
            )
        except cv2.error:
            return None
        if rho < self.min_correlation:
            return None
        homography = _translation(lo) @ np.linalg.inv(warp.astype(np.float64)) @ placed
        corners = apply_homography(homography, self.plane_corners)
        if np.abs(corners - prediction.corners).max() > prediction.search_px + 2:
            return None
        if not self._reads_id(grey, homography, prediction.landmark_id):
            return None
        plane = square_centres(prediction.landmark_id, self.pattern)
        return Detection(
            landmark_id=prediction.landmark_id,
            image_points=apply_homography(homography, plane),
            plane_points=plane,
            indices=np.arange(len(plane), dtype=np.int64),
            score=float(rho),
            homography=homography,
            corners=corners,
        )

    def _draw(
        self, landmark_id: int, plane_to_pixels: np.ndarray, shape: tuple[int, int]
    ) -> tuple[np.ndarray, np.ndarray]:
        """The board (white squares 1, black 0), area-sampled into a ``shape`` image through
        the homography, and the uint8 mask of the pixels wholly on the board."""
        texture, texture_to_plane = self._texture(landmark_id)
        to_super = np.array(
            [[SUPERSAMPLE, 0, (SUPERSAMPLE - 1) / 2], [0, SUPERSAMPLE, (SUPERSAMPLE - 1) / 2]]
        )
        warp = np.vstack([to_super, [0, 0, 1]]) @ plane_to_pixels @ texture_to_plane
        size = (shape[1] * SUPERSAMPLE, shape[0] * SUPERSAMPLE)
        fine = cv2.warpPerspective(texture, warp, size, flags=cv2.INTER_LINEAR)
        board = cv2.warpPerspective(np.ones_like(texture), warp, size, flags=cv2.INTER_NEAREST)
        small = (shape[1], shape[0])
        template = cv2.resize(fine, small, interpolation=cv2.INTER_AREA)
        mask = cv2.resize(board, small, interpolation=cv2.INTER_AREA) >= 0.999
        return template, mask.astype(np.uint8)

    def _texture(self, landmark_id: int) -> tuple[np.ndarray, np.ndarray]:
        """The board's image (float32, 0..1) and the map from its pixels to the plane (m)."""
        if landmark_id not in self._textures:
            image = landmark_image(landmark_id, self.pattern).astype(np.float32) / 255
            scale, half = image.shape[0] / self.pattern.size, self.pattern.size / 2
            to_plane = np.array(
                [[1 / scale, 0, 0.5 / scale - half], [0, -1 / scale, half - 0.5 / scale], [0, 0, 1]]
            )
            self._textures[landmark_id] = image, to_plane
        return self._textures[landmark_id]

    def _reads_id(self, grey: np.ndarray, homography: np.ndarray, landmark_id: int) -> bool:
        """Whether the board under ``homography`` reads ``landmark_id``: every cell lit for
        that id brighter, every other cell darker, than the midpoint of the board's black
        border and its always-lit squares."""
        samples = _sample(grey, apply_homography(homography, self._cells))
        black = float(np.median(_sample(grey, apply_homography(homography, self._border))))
        g = self.pattern.grid
        lit = np.zeros(g * g, bool)
        for r, c in lit_cells(landmark_id, self.pattern):
            lit[r * g + c] = True
        white = float(np.median(samples[lit]))
        if white - black < self.min_contrast:
            return False
        middle = 0.5 * (white + black)
        return bool((samples[lit] > middle).all() and (samples[~lit] < middle).all())


def _translation(offset) -> np.ndarray:
    t = np.eye(3)
    t[:2, 2] = offset
    return t


def _sample(grey: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Bilinear grey values at ``points`` (N, 2)."""
    at = points.astype(np.float32)[:, None, :]
    return cv2.remap(grey, at, None, cv2.INTER_LINEAR).ravel().astype(np.float64)


def _best_shift(window: np.ndarray, template: np.ndarray, mask: np.ndarray) -> np.ndarray | None:
    """The placement (top-left pixel) of ``template`` in ``window`` with the largest masked
    normalised cross-correlation (eq. 7)."""
    ncc = cv2.matchTemplate(window, template, cv2.TM_CCOEFF_NORMED, mask=mask)
    ncc[~np.isfinite(ncc)] = -1.0
    _, best, _, (x, y) = cv2.minMaxLoc(ncc)
    if best <= 0:
        return None
    return np.array([x, y], dtype=np.float32)
