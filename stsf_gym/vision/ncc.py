"""Normalised cross-correlation of an image with a small template (paper eq. 7, normalised).

For a template ``g`` of ``n`` pixels and the image window ``f`` at each position::

    M'(i, j) = (sum f g - sum f * mean g) / sqrt(max(sum f^2 - (sum f)^2 / n, n s^2) * G)

with ``G = sum (g - mean g)^2``: the correlation coefficient of OpenCV's ``TM_CCOEFF_NORMED``
(see :mod:`stsf_gym.vision.template`), except that windows whose grey-level standard
deviation is below ``s = MIN_WINDOW_STD`` count as having that much (a regularised
coefficient). Such windows are flat to the eye, their correlation is pixel noise, and no
board is that flat; with the floor they score below any useful threshold instead of
anywhere in [-1, 1].

It is computed from OpenCV's plain correlation ``TM_CCORR`` (Intel IPP where OpenCV has it)
and two box filters for the window sums: about two thirds of the time of
``TM_CCOEFF_NORMED``, whose per-pixel normalisation in double precision is most of its cost.
Window sums are float32, exact while below 2^24 (templates up to 16 x 16 pixels).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

__all__ = ["MIN_WINDOW_STD", "CorrelationTemplate", "correlate"]

MIN_WINDOW_STD = 2.0  # grey levels: flatter windows are treated as this contrasted


class CorrelationTemplate:
    """A uint8 template with the constants :func:`correlate` needs."""

    def __init__(self, image: np.ndarray) -> None:
        image = np.ascontiguousarray(image)
        if image.dtype != np.uint8 or image.ndim != 2:
            raise ValueError(f"template must be a 2-D uint8 array, got {image.dtype} {image.shape}")
        values = image.astype(np.float64)
        self.image = image
        self.shape = image.shape
        self.area = image.size
        self.mean = float(values.mean())
        self.norm = math.sqrt(float(((values - self.mean) ** 2).sum()))  # sqrt(G)
        if self.norm == 0:
            raise ValueError("template must not be flat")


def correlate(image: np.ndarray, template: CorrelationTemplate) -> np.ndarray:
    """``M'`` (float32) at every position where the template fits inside the uint8 ``image``:
    shape ``(H - h + 1, W - w + 1)``, entry ``[i, j]`` for the window whose top-left pixel is
    ``image[i, j]``."""
    h, w = template.shape
    num = cv2.matchTemplate(image, template.image, cv2.TM_CCORR)
    rows, cols = num.shape
    box = (w, h)
    sums = cv2.boxFilter(image, cv2.CV_32F, box, anchor=(0, 0), normalize=False)[:rows, :cols]
    squares = cv2.sqrBoxFilter(image, cv2.CV_32F, box, anchor=(0, 0), normalize=False)
    num = cv2.scaleAdd(sums, -template.mean, num)
    spread = cv2.subtract(squares[:rows, :cols], cv2.multiply(sums, sums, scale=1 / template.area))
    spread = cv2.max(spread, template.area * MIN_WINDOW_STD**2)
    return cv2.divide(num, cv2.sqrt(spread), scale=1 / template.norm)
