"""Landmark detector of the paper's sect. 3.1: template matching, then sub-pixel square centres.

The detector runs in two stages.

1. **Candidates by template matching** (paper eq. 6-7): local maxima of the normalised
   cross-correlation with a blurred board template over an image pyramid, see
   :mod:`stsf_gym.vision.template`.

2. **Geometry** on the full-resolution image around each candidate, best first: the board's
   dark region, its white squares, their grid cells (which give the id), sub-pixel square
   centres and a least-squares homography, see :mod:`stsf_gym.vision.board`. The region of
   interest grows while the board touches its edge (unless that edge is the frame's).

Assumptions: the board is seen from its front, with image roll under 45 degrees (the ring
and centre are symmetric under 90 degree turns, so "up" is taken from the image), whole
inside the frame and at least about ``min_board_px`` pixels wide. Pixel coordinates have
pixel centres at integers (the convention of ``env.unwrapped.camera_matrix``).

This module does not import PyBullet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from stsf_gym.vision.board import GROW, BoardFit, BoardFitter, apply_homography
from stsf_gym.vision.landmarks import LandmarkPattern
from stsf_gym.vision.template import Candidate, TemplateMatcher

__all__ = ["Detection", "LandmarkDetector", "to_grey"]

ROI_HALF_SIDE = 0.9  # first region of interest: this many candidate sizes either side (+2 px)
ROI_GROWTH = 1.7  # factor by which the region grows while the board touches its edge
ROI_TRIES = 3  # region sizes tried per candidate


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
    #: 3x3, landmark plane (m) -> image (px); None where none was fitted (the estimators'
    #: undistorted copies, which use the points themselves): :meth:`project` fits one then
    homography: np.ndarray | None = field(repr=False)
    reprojection_rms: float = 0.0  # px, image_points vs homography @ plane_points
    corners: np.ndarray = field(default=None, repr=False)  # (4, 2) board corners in pixels

    def project(self, plane_xy: np.ndarray) -> np.ndarray:
        """Pixels of landmark-plane points (..., 2) through the fitted homography."""
        homography = self.homography
        if homography is None:
            homography, _ = cv2.findHomography(self.plane_points, self.image_points)
        return apply_homography(homography, np.asarray(plane_xy, dtype=np.float64))


def to_grey(image: np.ndarray) -> np.ndarray:
    """The uint8 grey image of an HxW grey or HxWx3(4) RGB(A) uint8 image."""
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

    ``detect`` is stateless: each call depends on its image only. For debugging, set
    ``detector.fitter.trace = []`` to collect the reasons candidates were rejected.
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
        self.fitter = BoardFitter(self.pattern, max_reprojection_px, valid_ids)
        self.max_candidates = int(max_candidates)

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

    @property
    def valid_ids(self) -> set[int] | None:
        """Ids accepted (None: all)."""
        return self.fitter.valid_ids

    @property
    def max_reprojection_px(self) -> float:
        """Largest RMS reprojection error of an accepted board, pixels."""
        return self.fitter.max_reprojection_px

    def candidates(self, grey: np.ndarray) -> list[Candidate]:
        """Candidate board regions of stage 1 (eq. 6-7) in a uint8 grey image, best first."""
        return self.matcher.candidates(grey)

    def detect(self, image: np.ndarray) -> list[Detection]:
        """Landmarks in ``image`` (HxW grey or HxWx3 RGB, uint8), best NCC score first."""
        grey = to_grey(image)
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

    def detect_at(self, grey: np.ndarray, cx: float, cy: float, size: float) -> Detection | None:
        """The board around ``(cx, cy)`` of side about ``size`` px (a track's prediction), by
        stage 2 alone: no template search. Its ``score`` is NaN (no correlation was taken)."""
        return self._verify(grey, Candidate(cx, cy, size, math.nan))

    def _verify(self, grey: np.ndarray, cand: Candidate) -> Detection | None:
        """The landmark around a candidate, growing the region while the board touches its edge."""
        h, w = grey.shape
        half = ROI_HALF_SIDE * cand.size + 2
        for _ in range(ROI_TRIES):
            x0, y0 = max(0, math.floor(cand.cx - half)), max(0, math.floor(cand.cy - half))
            x1, y1 = min(w, math.ceil(cand.cx + half) + 1), min(h, math.ceil(cand.cy + half) + 1)
            if x1 - x0 < 8 or y1 - y0 < 8:
                return None
            fit = self.fitter.fit(grey, x0, y0, x1, y1)
            if fit is not GROW:
                return None if fit is None else _detection(fit, cand.score, self.fitter.board_xy)
            half *= ROI_GROWTH
        return None


def _detection(fit: BoardFit, score: float, board_xy: np.ndarray) -> Detection:
    """The detection of a fitted board; ``board_xy``: the board's plane corners."""
    return Detection(
        landmark_id=fit.landmark_id,
        image_points=fit.image_points,
        plane_points=fit.plane_points,
        indices=np.arange(len(fit.plane_points), dtype=np.int64),
        score=score,
        homography=fit.homography,
        reprojection_rms=fit.reprojection_rms,
        corners=apply_homography(fit.homography, board_xy),
    )


def _inside(corners: np.ndarray, x: float, y: float) -> bool:
    if corners is None:
        return False
    return cv2.pointPolygonTest(corners.astype(np.float32), (float(x), float(y)), False) >= 0
