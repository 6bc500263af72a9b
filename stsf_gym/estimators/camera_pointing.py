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
from stsf_gym.geometry import compiled

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

    def centre(self, index: int) -> np.ndarray:
        """The floor position (x, y) of the board of the landmark at ``index`` (map order)."""
        return self._centres[index]

    def _camera_xy(self, pose: np.ndarray) -> np.ndarray:
        return pose[:2] + self.camera_forward * np.array([math.cos(pose[2]), math.sin(pose[2])])

    def in_sight(self, pose: np.ndarray) -> list[tuple[int, float]]:
        """(index, bearing from the camera, rad off the heading) of every landmark within
        range, facing the camera within the viewing angle and with no wall in the line of
        sight from ``pose``, whatever the pan limit; in map order."""
        eye = self._camera_xy(pose)
        seen = _in_sight(
            eye,
            self._centres,
            self._normals,
            self._walls,
            self.min_range,
            self.max_range,
            math.cos(self.max_view),
        )
        sighted = []
        for index in np.flatnonzero(seen):
            to_board = self._centres[index] - eye
            bearing = math.remainder(math.atan2(to_board[1], to_board[0]) - pose[2], math.tau)
            sighted.append((int(index), bearing))
        return sighted

    def candidates(self, pose: np.ndarray) -> list[tuple[int, float]]:
        """(index, pan) of every landmark that qualifies from ``pose``, in map order: those
        :meth:`in_sight` within the pan limit."""
        return [(i, pan) for i, pan in self.in_sight(pose) if abs(pan) <= self.pan_limit]

    def pan(self, pose: np.ndarray) -> float:
        """Pan towards the best-scoring landmark (0 if none qualifies). The current target
        keeps an advantage of ``SWITCH_FACTOR`` so the choice does not flicker."""
        best = None
        for index, pan in self.candidates(pose):
            # motion stereo needs parallax: favour landmarks off the direction of travel
            distance = float(np.hypot(*(self._centres[index] - pose[:2])))
            score = distance / max(abs(math.sin(pan)), MIN_SIDEWAYS)
            if self._ids[index] == self.target:
                score /= SWITCH_FACTOR
            if best is None or score < best[0]:
                best = (score, int(self._ids[index]), pan)
        self.target = None if best is None else best[1]
        return 0.0 if best is None else best[2]


@compiled
def _in_sight(
    eye: np.ndarray,
    centres: np.ndarray,
    normals: np.ndarray,
    walls: np.ndarray,
    min_range: float,
    max_range: float,
    cos_max_view: float,
) -> np.ndarray:
    """Whether each landmark (board ``centres``, outward ``normals``) is within ``[min_range,
    max_range]`` of ``eye``, faces it within the view angle, and no wall ``[x1, y1, x2, y2]``
    crosses the line of sight from ``eye`` to 0.2 m in front of the board (clear of its own
    wall): ``r = target - eye``, ``s = end - start``, crossing at ``t = (q - eye) x s / (r x
    s)`` in (0, 1) and ``u = (q - eye) x r / (r x s)`` in [0, 1], ``r x s`` not ~0."""
    seen = np.zeros(centres.shape[0], dtype=np.bool_)
    for i in range(centres.shape[0]):
        to_x, to_y = centres[i, 0] - eye[0], centres[i, 1] - eye[1]
        distance = np.hypot(to_x, to_y)
        facing = -(normals[i, 0] * to_x + normals[i, 1] * to_y)
        if not (min_range <= distance <= max_range and facing / distance >= cos_max_view):
            continue
        r_x = centres[i, 0] + 0.2 * normals[i, 0] - eye[0]
        r_y = centres[i, 1] + 0.2 * normals[i, 1] - eye[1]
        seen[i] = True
        for wall in walls:
            s_x, s_y = wall[2] - wall[0], wall[3] - wall[1]
            q_x, q_y = wall[0] - eye[0], wall[1] - eye[1]
            denominator = r_x * s_y - r_y * s_x
            t = (q_x * s_y - q_y * s_x) / denominator
            u = (q_x * r_y - q_y * r_x) / denominator
            if abs(denominator) > 1e-12 and 0 < t < 1 and 0 <= u <= 1:
                seen[i] = False
                break
    return seen
