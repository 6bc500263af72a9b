"""Keeping the pan camera on a landmark, from the pose estimate and the map only.

The target is a map landmark whose board faces the robot within ``max_view_deg`` of its
normal, lies within ``[min_range, max_range]`` and within the pan limits; among those, the
nearest one off the direction of travel (distance over the sine of the pan), since motion
stereo needs parallax. The current target is only given up for a clearly better one
(hysteresis), so tracks are not cut by flickering choices. The pan
angle points the camera at the target's centre from the estimated camera position.
"""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.estimators.base import MapLandmark

MIN_SIDEWAYS = 0.2  # sine of the smallest pan counted when scoring a landmark
SWITCH_FACTOR = 1.5  # how much better another landmark must score to take over
RANGE_MARGIN = 1e-6  # m: the range pre-filter keeps this much more than the exact test


class LandmarkPointer:
    """Pan angle (rad) that keeps a landmark in view, from the estimated pose."""

    def __init__(
        self,
        landmarks: dict[int, MapLandmark],
        walls: np.ndarray,
        camera_forward: float,
        pan_limit: float,
        min_range: float = 1.0,
        max_range: float = 8.0,
        max_view_deg: float = 65.0,
    ) -> None:
        self.landmarks, self.walls = landmarks, np.asarray(walls, dtype=float).reshape(-1, 4)
        self.camera_forward, self.pan_limit = camera_forward, pan_limit
        self.min_range, self.max_range = min_range, max_range
        self.max_view = math.radians(max_view_deg)
        self.target: int | None = None

    @property
    def landmarks(self) -> dict[int, MapLandmark]:
        """The map's landmarks by id."""
        return self._landmarks

    @landmarks.setter
    def landmarks(self, landmarks: dict[int, MapLandmark]) -> None:
        self._landmarks = landmarks
        self._centres = np.array([lm.centre[:2] for lm in landmarks.values()]).reshape(-1, 2)

    def reset(self) -> None:
        """Forget the landmark the camera was kept on."""
        self.target = None

    def _in_range(self, pose: np.ndarray) -> list[MapLandmark]:
        """The landmarks near enough to qualify, in map order: a cheap pre-filter on all of them
        at once, wider by :data:`RANGE_MARGIN` than :meth:`_pan_to`'s exact test, which then
        decides as before (the same choice to the last bit, in a fraction of the time)."""
        offsets = self._centres - self._camera_xy(pose)
        squared = offsets[:, 0] ** 2 + offsets[:, 1] ** 2
        low = max(self.min_range - RANGE_MARGIN, 0.0) ** 2
        high = (self.max_range + RANGE_MARGIN) ** 2
        near = (squared >= low) & (squared <= high)
        return [lm for lm, keep in zip(self._landmarks.values(), near, strict=True) if keep]

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
        if abs(pan) > self.pan_limit or self._blocked(self._camera_xy(pose), landmark):
            return None
        return pan

    def _blocked(self, eye: np.ndarray, landmark: MapLandmark) -> bool:
        """Whether a wall of the map crosses the line of sight (stopping short of the board)."""
        target = landmark.centre[:2] + 0.2 * landmark.normal[:2]  # clear of its own wall
        p, r = eye, target - eye
        q, s = self.walls[:, :2], self.walls[:, 2:] - self.walls[:, :2]
        denom = r[0] * s[:, 1] - r[1] * s[:, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((q[:, 0] - p[0]) * s[:, 1] - (q[:, 1] - p[1]) * s[:, 0]) / denom
            u = ((q[:, 0] - p[0]) * r[1] - (q[:, 1] - p[1]) * r[0]) / denom
        return bool(np.any((np.abs(denom) > 1e-12) & (t > 0) & (t < 1) & (u >= 0) & (u <= 1)))

    def pan(self, pose: np.ndarray) -> float:
        """Pan towards the best-scoring landmark (0 if none qualifies). The current target
        keeps an advantage of ``SWITCH_FACTOR`` so the choice does not flicker."""
        best = None
        for landmark in self._in_range(pose):
            pan = self._pan_to(landmark, pose)
            if pan is None:
                continue
            # motion stereo needs parallax: favour landmarks off the direction of travel
            distance = float(np.hypot(*(landmark.centre[:2] - pose[:2])))
            score = distance / max(abs(math.sin(pan)), MIN_SIDEWAYS)
            if landmark.id == self.target:
                score /= SWITCH_FACTOR
            if best is None or score < best[0]:
                best = (score, landmark.id, pan)
        self.target = None if best is None else best[1]
        return 0.0 if best is None else best[2]
