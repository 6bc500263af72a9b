"""Pinhole camera: the true intrinsics and distortion, and the OpenGL matrices renderers use.

Camera axes follow OpenCV (x right, y down, z forward). The renderers draw with OpenGL axes
(x right, y up, z backward) and an OpenGL projection; the two are built here from the same
numbers, so a world point projected through K (and the lens's distortion, applied to the
rendered frame by :mod:`stsf_gym.envs.sensors.lens`) lands where the renderer draws it (pixel
centres at integer coordinates; with the default K the principal point is ``(W/2 - 0.5, H/2 -
0.5)``).
"""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.camera_model import CameraCalibration
from stsf_gym.envs.config import CalibrationErrorConfig
from stsf_gym.validation import ConfigError

#: Maps OpenCV camera axes to OpenGL camera axes (and back): flip y and z.
CV_TO_GL = np.diag([1.0, -1.0, -1.0, 1.0])


def projection_from_K(K: np.ndarray, width: int, height: int, near: float, far: float):
    """OpenGL projection (row-major 4x4) drawing pixel centres where OpenCV's ``K`` puts them.

    Pixel ``(u, v)`` (OpenCV, top row 0) covers window coordinates centred at ``(u + 0.5,
    H - v - 0.5)``; the image is read back bottom row first and flipped.
    """
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    n, f = near, far
    return np.array(
        [
            [2 * fx / width, 0, 1 - 2 * (cx + 0.5) / width, 0],
            [0, 2 * fy / height, 2 * (cy + 0.5) / height - 1, 0],
            [0, 0, (f + n) / (n - f), 2 * f * n / (n - f)],
            [0, 0, -1, 0],
        ]
    )


class PinholeCamera:
    """A ``width x height`` camera with vertical field of view ``vfov_deg`` (of K) and the
    lens distortion ``dist`` (OpenCV ``k1 k2 p1 p2 k3``)."""

    def __init__(
        self,
        width: int,
        height: int,
        vfov_deg: float,
        near: float,
        far: float,
        dist: np.ndarray | tuple = (0.0,) * 5,
    ) -> None:
        if width <= 0 or height <= 0:
            raise ConfigError(f"camera size must be positive, got {width}x{height}")
        if not 0 < vfov_deg < 180:
            raise ConfigError(f"camera.vfov_deg must be in (0, 180), got {vfov_deg}")
        if not 0 < near < far:
            raise ConfigError(f"camera near/far must satisfy 0 < near < far, got {near}, {far}")
        self.width, self.height = width, height
        self.vfov = math.radians(vfov_deg)
        self.near, self.far = near, far
        f = (height / 2) / math.tan(self.vfov / 2)
        K = np.array([[f, 0.0, width / 2 - 0.5], [0.0, f, height / 2 - 0.5], [0.0, 0.0, 1.0]])
        self.calibration = CameraCalibration(K, np.asarray(dist, float))
        self._inverse: tuple[np.ndarray, np.ndarray] | None = None  # the last pose, inverted

    @property
    def focal_px(self) -> float:
        return float(self.K[0, 0])

    @property
    def K(self) -> np.ndarray:
        return self.calibration.K

    @property
    def dist(self) -> np.ndarray:
        return self.calibration.dist

    def projection_matrix(self) -> np.ndarray:
        """OpenGL projection of K (without the distortion)."""
        return projection_from_K(self.K, self.width, self.height, self.near, self.far)

    def project(self, world_from_camera: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Pixel coordinates (N, 2) of world points (N, 3) through K and the distortion, as
        ``cv2.projectPoints``; points behind the camera give NaN."""
        camera_from_world = self._camera_from_world(world_from_camera)
        pc = points @ camera_from_world[:3, :3].T + camera_from_world[:3, 3]
        return self.calibration.project(pc)

    def _camera_from_world(self, world_from_camera: np.ndarray) -> np.ndarray:
        """The pose's inverse, kept for the next call from the same pose (a frame projects
        several sets of points from one)."""
        pose = np.asarray(world_from_camera, dtype=float)
        last = self._inverse
        if last is None or last[0].shape != pose.shape or not (last[0] == pose).all():
            self._inverse = last = (pose.copy(), np.linalg.inv(pose))
        return last[1]


def believed_calibration(
    true: CameraCalibration, error: CalibrationErrorConfig, rng: np.random.Generator
) -> CameraCalibration:
    """The calibration the robot believes it has: ``true`` with this episode's errors (focal
    length relative, principal point in pixels, each distortion coefficient), drawn from
    ``rng`` like the wheels' calibration errors."""
    focal, centre, dist = rng.normal(size=(3,)), rng.normal(size=(2,)), rng.normal(size=(5,))
    K = true.K.copy()
    K[:2, :2] *= 1 + error.focal_std * focal[0]
    K[:2, 2] += error.principal_point_std_px * centre
    return CameraCalibration(K, true.dist + np.asarray(error.distortion_std) * dist)


def view_matrix(world_from_camera: np.ndarray) -> np.ndarray:
    """OpenGL view matrix (row-major 4x4) of a camera pose given with OpenCV axes."""
    return np.linalg.inv(world_from_camera @ CV_TO_GL)


def look_at(eye: np.ndarray, target: np.ndarray, up: np.ndarray) -> np.ndarray:
    """World-from-camera pose (OpenCV axes) of a camera at ``eye`` looking at ``target``."""
    z = np.asarray(target, float) - np.asarray(eye, float)
    z /= np.linalg.norm(z)
    x = np.cross(z, up)
    x /= np.linalg.norm(x)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    pose[:3, 3] = eye
    return pose
