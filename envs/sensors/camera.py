"""Pinhole camera: the intrinsic matrix K and the OpenGL matrices PyBullet renders with.

Camera axes follow OpenCV (x right, y down, z forward). PyBullet renders with OpenGL axes
(x right, y up, z backward) and an OpenGL projection; the two are built here from the same
numbers, so a world point projected through :attr:`PinholeCamera.K` and the pose lands where
the renderer draws it (pixel centres at integer coordinates, principal point at
``(W/2 - 0.5, H/2 - 0.5)``).
"""

from __future__ import annotations

import math

import numpy as np

#: Maps OpenCV camera axes to OpenGL camera axes (and back): flip y and z.
CV_TO_GL = np.diag([1.0, -1.0, -1.0, 1.0])


class PinholeCamera:
    """Intrinsics of a ``width x height`` camera with vertical field of view ``vfov_deg``."""

    def __init__(self, width: int, height: int, vfov_deg: float, near: float, far: float):
        if width <= 0 or height <= 0:
            raise ValueError(f"camera size must be positive, got {width}x{height}")
        if not 0 < vfov_deg < 180:
            raise ValueError(f"camera.vfov_deg must be in (0, 180), got {vfov_deg}")
        if not 0 < near < far:
            raise ValueError(f"camera near/far must satisfy 0 < near < far, got {near}, {far}")
        self.width, self.height = width, height
        self.vfov = math.radians(vfov_deg)
        self.near, self.far = near, far

    @property
    def focal_px(self) -> float:
        return (self.height / 2) / math.tan(self.vfov / 2)

    @property
    def K(self) -> np.ndarray:
        f = self.focal_px
        return np.array(
            [[f, 0.0, self.width / 2 - 0.5], [0.0, f, self.height / 2 - 0.5], [0.0, 0.0, 1.0]]
        )

    @property
    def hfov(self) -> float:
        return 2 * math.atan((self.width / 2) / self.focal_px)

    def projection_matrix(self) -> np.ndarray:
        """OpenGL projection (row-major 4x4), as ``computeProjectionMatrixFOV`` builds it."""
        y_scale = 1 / math.tan(self.vfov / 2)
        x_scale = y_scale * self.height / self.width
        n, f = self.near, self.far
        return np.array(
            [
                [x_scale, 0, 0, 0],
                [0, y_scale, 0, 0],
                [0, 0, (f + n) / (n - f), 2 * f * n / (n - f)],
                [0, 0, -1, 0],
            ]
        )

    def project(self, world_from_camera: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Pixel coordinates (N, 2) of world points (N, 3); points behind the camera give NaN."""
        camera_from_world = np.linalg.inv(world_from_camera)
        pc = points @ camera_from_world[:3, :3].T + camera_from_world[:3, 3]
        uvw = pc @ self.K.T
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = uvw[:, :2] / uvw[:, 2:3]
        uv[pc[:, 2] <= 0] = np.nan
        return uv


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
