"""Keeping the pan camera on a landmark, from the pose estimate and the map only.

The target is the nearest map landmark whose board faces the robot within ``max_view_deg``
of its normal, lies within ``[min_range, max_range]`` and within the pan limits; it is kept
until it stops qualifying (hysteresis), so tracks are not cut by flickering choices. The pan
angle points the camera at the target's centre from the estimated camera position.
"""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.estimators.base import MapLandmark


class LandmarkPointer:
    """Pan angle (rad) that keeps a landmark in view, from the estimated pose."""

    def __init__(
        self,
        landmarks: dict[int, MapLandmark],
        camera_forward: float,
        pan_limit: float,
        min_range: float = 1.0,
        max_range: float = 8.0,
        max_view_deg: float = 65.0,
    ) -> None:
        self.landmarks, self.camera_forward, self.pan_limit = landmarks, camera_forward, pan_limit
        self.min_range, self.max_range = min_range, max_range
        self.max_view = math.radians(max_view_deg)
        self.target: int | None = None

    def reset(self) -> None:
        self.target = None

    def _camera_xy(self, pose: np.ndarray) -> np.ndarray:
        return pose[:2] + self.camera_forward * np.array([math.cos(pose[2]), math.sin(pose[2])])

    def _pan_to(self, landmark: MapLandmark, pose: np.ndarray) -> float | None:
        """The pan towards ``landmark``, or ``None`` if it does not qualify from ``pose``."""
        to_board = landmark.centre[:2] - self._camera_xy(pose)
        distance = float(np.hypot(*to_board))
        if not self.min_range <= distance <= self.max_range:
            return None
        facing = -float(landmark.normal[:2] @ to_board) / distance  # cos of the viewing angle
        if facing < math.cos(self.max_view):
            return None
        pan = math.remainder(math.atan2(to_board[1], to_board[0]) - pose[2], math.tau)
        return pan if abs(pan) <= self.pan_limit else None

    def pan(self, pose: np.ndarray) -> float:
        """Pan for the current target, choosing a new one when needed (0 if none qualifies)."""
        if self.target is not None:
            pan = self._pan_to(self.landmarks[self.target], pose)
            if pan is not None:
                return pan
        best = None
        for landmark in self.landmarks.values():
            pan = self._pan_to(landmark, pose)
            if pan is not None:
                distance = float(np.hypot(*(landmark.centre[:2] - pose[:2])))
                if best is None or distance < best[0]:
                    best = (distance, landmark.id, pan)
        if best is None:
            self.target = None
            return 0.0
        self.target = best[1]
        return best[2]
