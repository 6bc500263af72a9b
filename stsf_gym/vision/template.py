"""Candidate landmark regions by template matching (paper sect. 3.1, eq. 6-7).

The paper scores how well a template ``g(m, n)`` fits the image ``f(i, j)`` at ``(i, j)`` by
the distance ``d = sum_G (f - g)^2`` (eq. 6), whose minimum is the maximum of the
cross-correlation ``M(i, j) = sum_m sum_n f(i + m, j + n) g(m, n)`` (eq. 7). Plain eq. 7
depends on the image's brightness and contrast, so we use its normalised form, the
correlation coefficient (OpenCV ``TM_CCOEFF_NORMED``)::

    M'(i, j) = sum (f(i+m, j+n) - mean f) (g(m, n) - mean g)
               / sqrt(sum (f - mean f)^2 * sum (g - mean g)^2)      in [-1, 1]

which is eq. 7 after removing the local mean and dividing by the local energy; its maximum
is the minimum of eq. 6 under an affine change of grey levels. It is computed by
:func:`stsf_gym.vision.ncc.correlate`, which also scores flat windows low. The template is
the board of :mod:`stsf_gym.vision.landmarks` with the ring and centre squares white and the
id cells half grey (their mean over all ids), in a light margin, blurred. It is matched at
two sizes per octave of a box-filtered image pyramid (whole-factor box averages, OpenCV's
fast resize path), so the cost stays that of a few small correlations on a small image;
local maxima above ``ncc_threshold`` are the candidate regions, which
:class:`~stsf_gym.vision.detector.LandmarkDetector` then verifies. The correlations are most
of this stage's time; peaks are gathered and suppressed with array operations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from stsf_gym.vision.landmarks import LandmarkPattern, landmark_image
from stsf_gym.vision.ncc import CorrelationTemplate, correlate

__all__ = ["Candidate", "TemplateMatcher"]

TEMPLATE_MARGIN = 0.15  # wall around the board in the template, in board sides
TEMPLATE_WALL = 0.6  # its grey level (fraction of white): walls are lighter than the board
BLUR_PER_PX = 0.1  # Gaussian sigma of template and image, per pixel of the smallest template
BLUR_RADIUS = 2.5  # the image's Gaussian kernel reaches this many sigmas either side


@dataclass(frozen=True)
class Candidate:
    """A region that may hold a board, in full-resolution pixels."""

    cx: float  # centre, pixels
    cy: float
    size: float  # board side, pixels
    score: float  # NCC (eq. 7, normalised)


class TemplateMatcher:
    """Local maxima of the normalised eq. 7 over positions and board sizes.

    ``ncc_threshold``, ``min_board_px``, ``max_board_px`` and ``template_px`` are those of
    :class:`~stsf_gym.vision.detector.LandmarkDetector`; at most ``max_peaks`` local maxima
    (best first) are kept per NCC map.
    """

    def __init__(
        self,
        pattern: LandmarkPattern,
        *,
        ncc_threshold: float,
        min_board_px: float,
        max_board_px: float | None,
        template_px: int,
        max_peaks: int,
    ) -> None:
        if template_px < 6:
            raise ValueError(f"template_px must be at least 6, got {template_px}")
        if min_board_px < template_px:
            raise ValueError(f"min_board_px ({min_board_px}) must be >= template_px")
        self.pattern = pattern
        self.ncc_threshold = float(ncc_threshold)
        self.min_board_px = float(min_board_px)
        self.max_board_px = None if max_board_px is None else float(max_board_px)
        self.template_px = int(template_px)
        self.max_peaks = int(max_peaks)
        self._templates = self._make_templates()
        self._plan_cache: dict[tuple[int, int], tuple[float, list[list[int]]]] = {}

    def _make_templates(self) -> dict[int, CorrelationTemplate]:
        """Templates by board side ``s`` (pixels).

        The board (ring and centre white, id cells half grey: their mean over all ids) sits
        in a margin of ``TEMPLATE_MARGIN`` board sides of light grey (the wall) and is blurred
        by ``BLUR_PER_PX * s``: at these sizes the squares are barely resolved, and the blur
        makes the correlation peak tolerant to the scale step, perspective and pixel phase.
        """
        p = self.pattern
        px_per_m = 40.0 / p.pitch  # 40 px per pitch: fine enough for any template size
        base = landmark_image(0, p, px_per_m).astype(np.float32)
        full = landmark_image(p.max_id, p, px_per_m).astype(np.float32)
        n = base.shape[0]
        m = round(TEMPLATE_MARGIN * n)
        hires = np.full((n + 2 * m, n + 2 * m), TEMPLATE_WALL * 255.0, np.float32)
        hires[m : m + n, m : m + n] = base + 0.5 * (full - base)
        out = {}
        for s in sorted({self.template_px, round(self.template_px * math.sqrt(2))}):
            side = round(s * (n + 2 * m) / n)
            tpl = cv2.resize(hires, (side, side), interpolation=cv2.INTER_AREA)
            tpl = cv2.GaussianBlur(tpl, (0, 0), BLUR_PER_PX * self.template_px)
            out[s] = CorrelationTemplate(np.rint(tpl).astype(np.uint8))
        return out

    def _plan(self, shape: tuple[int, int]) -> tuple[float, list[list[int]]]:
        """For an image shape: first shrink factor and the board sizes matched per octave."""
        key = (int(shape[0]), int(shape[1]))
        if key not in self._plan_cache:
            h, w = key
            max_board = self.max_board_px or min(h, w)
            shrink = max(1.0, self.min_board_px / self.template_px)
            octaves: list[list[int]] = []
            scale = shrink
            short = min(h, w) / shrink
            while self.template_px * scale <= max_board * 1.15:
                sizes = [
                    s
                    for s, tpl in self._templates.items()
                    if s * scale <= max_board * 1.2 and tpl.shape[0] < short
                ]
                if not sizes:
                    break
                octaves.append(sizes)
                scale *= 2
                short /= 2
            self._plan_cache[key] = (shrink, octaves)
        return self._plan_cache[key]

    def candidates(self, grey: np.ndarray) -> list[Candidate]:
        """Candidate board regions in a uint8 grey image, best NCC first.

        Returns candidates with NCC at least ``ncc_threshold``, with overlapping ones
        (centres closer than half a board) suppressed.
        """
        shrink, octaves = self._plan(grey.shape)
        if not octaves:
            return []
        level, (sx, sy) = _shrunk(grey, shrink)
        sigma = BLUR_PER_PX * self.template_px
        ksize = 2 * max(1, round(BLUR_RADIUS * sigma)) + 1
        found: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        maps: list[tuple[float, float, float, float]] = []  # side, board size, sx, sy
        for k, sizes in enumerate(octaves):
            if k:
                level, sx, sy = _halved(level), 2 * sx, 2 * sy
            blurred = cv2.GaussianBlur(level, (ksize, ksize), sigma)
            for s in sizes:
                tpl = self._templates[s]
                side = tpl.shape[0]
                if side >= min(level.shape):
                    continue
                peaks = self._peaks(correlate(blurred, tpl), s)
                if peaks is not None:
                    found.append(peaks)
                    maps.append((side, s, sx, sy))
        if not found:
            return []
        # One row per peak: its map's template side, board size and scale; then full pixels.
        side, size, sx, sy = np.repeat(maps, [len(p[0]) for p in found], axis=0).T
        ys, xs, score = (np.concatenate(c) for c in zip(*found, strict=True))
        peaks = np.stack(
            [(xs + side / 2) * sx - 0.5, (ys + side / 2) * sy - 0.5, size * 0.5 * (sx + sy), score],
            axis=1,
        )
        cx, cy, size, score = _suppress_overlaps(peaks).T
        return [
            Candidate(*c)
            for c in zip(cx.tolist(), cy.tolist(), size.tolist(), score.tolist(), strict=True)
        ]

    def _peaks(self, ncc: np.ndarray, s: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Rows, columns and scores of the local maxima of an NCC map (board side ``s``) at
        or above the threshold, at most ``max_peaks`` (the best); None if there are none."""
        if ncc.size == 0 or cv2.minMaxLoc(ncc)[1] < self.ncc_threshold:
            return None
        k = max(3, (s // 2) | 1)
        local_max = cv2.dilate(ncc, np.ones((k, k), np.uint8))
        # Flat indices: numpy's 1-D nonzero is many times faster than its 2-D one.
        at = ((ncc >= local_max) & (ncc >= self.ncc_threshold)).ravel().nonzero()[0]
        ys, xs = np.divmod(at, ncc.shape[1])
        score = ncc.ravel()[at].astype(np.float64)
        if len(xs) > self.max_peaks:
            best = np.argsort(score)[::-1][: self.max_peaks]
            ys, xs, score = ys[best], xs[best], score[best]
        return ys, xs, score


def _shrunk(grey: np.ndarray, shrink: float) -> tuple[np.ndarray, tuple[float, float]]:
    """``grey`` made about ``shrink`` times smaller, and the factors (x, y) it was shrunk by.

    It is box-averaged by the whole part of ``shrink`` (OpenCV's fast path for whole factors,
    after dropping the last rows and columns that do not fill a box), then resampled linearly
    by the rest.
    """
    if shrink <= 1.0:
        return grey, (1.0, 1.0)
    whole = int(shrink)
    h, w = (n - n % whole for n in grey.shape)
    if whole >= 2:
        grey = cv2.resize(grey[:h, :w], (w // whole, h // whole), interpolation=cv2.INTER_AREA)
    size = (max(1, round(w / shrink)), max(1, round(h / shrink)))
    if grey.shape[::-1] != size:
        grey = cv2.resize(grey, size, interpolation=cv2.INTER_LINEAR)
    return grey, (w / size[0], h / size[1])


def _halved(level: np.ndarray) -> np.ndarray:
    """``level`` box-averaged by 2 (its last row or column dropped when odd)."""
    h, w = level.shape[0] // 2, level.shape[1] // 2
    return cv2.resize(level[: 2 * h, : 2 * w], (w, h), interpolation=cv2.INTER_AREA)


def _suppress_overlaps(peaks: np.ndarray) -> np.ndarray:
    """Rows ``cx, cy, size, score`` best first, without those whose centre is within half a
    board of a better kept one (greedy non-maximum suppression)."""
    peaks = peaks[np.argsort(-peaks[:, 3], kind="stable")]
    x, y, s = peaks[:, 0], peaks[:, 1], peaks[:, 2]
    d2 = (x[:, None] - x[None, :]) ** 2 + (y[:, None] - y[None, :]) ** 2
    overlaps = d2 <= (0.5 * np.minimum(s[:, None], s[None, :])) ** 2
    suppressed = np.zeros(len(peaks), dtype=bool)
    keep = []
    for i in range(len(peaks)):
        if not suppressed[i]:
            keep.append(i)
            suppressed |= overlaps[i]
    return peaks[keep]
