"""A camera frame's landmark detections, whatever the camera mode.

With a rendered camera the detector runs on ``obs["image"]``; in the fast sensor mode the env
has already simulated its output (``obs["landmark_ids"]``, ``obs["landmark_points"]``, see
:mod:`envs.sensors.fast_camera`), which is unpacked into the same :class:`Detection` records,
so every estimator runs one code path in both modes.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

from stsf_gym.vision.detector import Detection, LandmarkDetector
from stsf_gym.vision.landmarks import LandmarkPattern, square_centres


class FrameDetector:
    """``detector(obs) -> list[Detection]`` for boards whose id is in ``valid_ids``."""

    def __init__(self, pattern: LandmarkPattern, valid_ids: set[int]) -> None:
        self.pattern, self.valid_ids = pattern, frozenset(valid_ids)

    def __call__(self, obs: dict) -> list[Detection]:
        if "landmark_ids" in obs:
            return self._unpack(obs["landmark_ids"], obs["landmark_points"])
        return _image_detector(self.pattern, self.valid_ids).detect(obs["image"])

    def _unpack(self, ids: np.ndarray, points: np.ndarray) -> list[Detection]:
        detections = []
        for landmark_id, slot in zip(ids.tolist(), points.reshape(len(ids), -1, 2), strict=True):
            if landmark_id not in self.valid_ids:
                continue
            plane = square_centres(landmark_id, self.pattern)
            image = slot[: len(plane)].astype(np.float64)
            homography, _ = cv2.findHomography(plane, image)
            if homography is None:
                continue
            detections.append(
                Detection(
                    landmark_id=landmark_id,
                    image_points=image,
                    plane_points=plane,
                    indices=np.arange(len(plane)),
                    score=1.0,
                    homography=homography,
                )
            )
        return detections


@lru_cache(maxsize=8)
def _image_detector(pattern: LandmarkPattern, valid_ids: frozenset[int]) -> LandmarkDetector:
    """One detector (its templates are costly to build) per pattern and map, per process."""
    return LandmarkDetector(pattern, valid_ids=set(valid_ids))
