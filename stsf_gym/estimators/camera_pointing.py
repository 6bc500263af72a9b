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
        self.landmarks, self.walls = landmarks, walls
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
        self._ids = np.array(list(landmarks), dtype=np.int64)
        self._centres = np.array([lm.centre[:2] for lm in landmarks.values()]).reshape(-1, 2)
        self._normals = np.array([lm.normal[:2] for lm in landmarks.values()]).reshape(-1, 2)

    @property
    def walls(self) -> np.ndarray:
        """The map's wall segments, one ``[x1, y1, x2, y2]`` a row."""
        return self._walls

    @walls.setter
    def walls(self, walls: np.ndarray) -> None:
        self._walls = np.asarray(walls, dtype=float).reshape(-1, 4)

    def reset(self) -> None:
        """Forget the landmark the camera was kept on."""
        self.target = None

    def _camera_xy(self, pose: np.ndarray) -> np.ndarray:
        return pose[:2] + self.camera_forward * np.array([math.cos(pose[2]), math.sin(pose[2])])

    def _candidates(self, pose: np.ndarray) -> list[tuple[int, float]]:
        """(index, pan) of every landmark that qualifies from ``pose``, in map order: range,
        viewing angle and pan limit for all landmarks at once, then the line of sight for the
        few left, all at once too (each number computed as the one-landmark tests did)."""
        eye = self._camera_xy(pose)
        to_board = self._centres - eye
        distance = np.hypot(to_board[:, 0], to_board[:, 1])
        facing = -(self._normals[:, 0] * to_board[:, 0] + self._normals[:, 1] * to_board[:, 1])
        near = (distance >= self.min_range) & (distance <= self.max_range)
        with np.errstate(divide="ignore", invalid="ignore"):
            near &= facing / distance >= math.cos(self.max_view)
        candidates = []
        for index in np.flatnonzero(near):
            pan = math.remainder(
                math.atan2(to_board[index, 1], to_board[index, 0]) - pose[2], math.tau
            )
            if abs(pan) <= self.pan_limit:
                candidates.append((int(index), pan))
        if not candidates:
            return candidates
        blocked = self._blocked(eye, np.array([index for index, _ in candidates]))
        return [pair for pair, hidden in zip(candidates, blocked, strict=True) if not hidden]

    def _blocked(self, eye: np.ndarray, indices: np.ndarray) -> np.ndarray:
        """Whether a wall of the map crosses the line of sight from ``eye`` to each landmark of
        ``indices`` (stopping short of the board): a segment intersection per (landmark,
        wall)."""
        target = self._centres[indices] + 0.2 * self._normals[indices]  # clear of its own wall
        r = (target - eye)[:, None, :]
        q, s = self._walls[None, :, :2], self._walls[None, :, 2:] - self._walls[None, :, :2]
        denom = r[..., 0] * s[..., 1] - r[..., 1] * s[..., 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((q[..., 0] - eye[0]) * s[..., 1] - (q[..., 1] - eye[1]) * s[..., 0]) / denom
            u = ((q[..., 0] - eye[0]) * r[..., 1] - (q[..., 1] - eye[1]) * r[..., 0]) / denom
        crossing = (np.abs(denom) > 1e-12) & (t > 0) & (t < 1) & (u >= 0) & (u <= 1)
        return np.any(crossing, axis=1)

    def pan(self, pose: np.ndarray) -> float:
        """Pan towards the best-scoring landmark (0 if none qualifies). The current target
        keeps an advantage of ``SWITCH_FACTOR`` so the choice does not flicker."""
        best = None
        for index, pan in self._candidates(pose):
            # motion stereo needs parallax: favour landmarks off the direction of travel
            distance = float(np.hypot(*(self._centres[index] - pose[:2])))
            score = distance / max(abs(math.sin(pan)), MIN_SIDEWAYS)
            if self._ids[index] == self.target:
                score /= SWITCH_FACTOR
            if best is None or score < best[0]:
                best = (score, int(self._ids[index]), pan)
        self.target = None if best is None else best[1]
        return 0.0 if best is None else best[2]
