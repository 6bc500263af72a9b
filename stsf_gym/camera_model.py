"""The pinhole camera with lens distortion, in OpenCV's conventions, in plain numpy.

Camera axes are OpenCV's (x right, y down, z forward); pixel centres sit at integer
coordinates. Distortion is Brown-Conrady radial-tangential with OpenCV's coefficient order
``k1 k2 p1 p2 k3``: a normalised point ``(x, y)``, ``r^2 = x^2 + y^2``, maps to

    x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
    y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y

and pixels are ``K @ [x_d, y_d, 1]``, so :meth:`CameraCalibration.project` agrees with
``cv2.projectPoints``. The simulator uses it for the true camera, the estimators for the
camera the robot believes it has (:attr:`CorridorEnv.camera_calibration`). :class:`PanTiltMount`
is where the camera sits on the robot: the simulated robot's mount kinematics, and what a
recorded log (:mod:`stsf_gym.recording`) stores of it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Annotated

import numpy as np

from stsf_gym.geometry import compiled
from stsf_gym.validation import ROBOT_EXTENT_M, Range, RobotLength

UNDISTORT_ITERATIONS = 20
INVERSE_TOLERANCE = 1e-6  # normalised units (a thousandth of a pixel at a 640 px focal length)
#: Rotation from the camera link (x forward, y left, z up) to OpenCV camera axes.
LINK_FROM_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def distort(xy: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """Distorted normalised coordinates (..., 2) of undistorted ones, in float64."""
    xy = np.asarray(xy, dtype=float)
    k1, k2, p1, p2, k3 = np.asarray(dist, dtype=float).tolist()
    return _distorted(xy.reshape(-1, 2), k1, k2, p1, p2, k3).reshape(xy.shape)


@compiled
def _distorted(xy: np.ndarray, k1: float, k2: float, p1: float, p2: float, k3: float) -> np.ndarray:
    """:func:`distort` of points (N, 2)."""
    xy_d = np.empty_like(xy)
    for i in range(xy.shape[0]):
        x, y = xy[i, 0], xy[i, 1]
        r2 = x * x + y * y
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        xy_d[i, 0] = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        xy_d[i, 1] = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return xy_d


def undistort(xy_d: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """Undistorted normalised coordinates of distorted ones: the fixed-point iteration of
    ``cv2.undistortPoints``, run to convergence for the distortions a lens has."""
    xy_d = np.asarray(xy_d, dtype=float)
    k1, k2, p1, p2, k3 = np.asarray(dist, dtype=float).tolist()
    flat = _undistorted(xy_d.reshape(-1, 2), k1, k2, p1, p2, k3, UNDISTORT_ITERATIONS)
    return flat.reshape(xy_d.shape)


def invertible(dist, corner: float, tolerance: float = INVERSE_TOLERANCE) -> bool:
    """Whether :func:`undistort` inverts distortion ``dist`` over the image: distorted points
    out to the normalised corner radius ``corner``, in eight directions, undistorted and
    distorted again land within ``tolerance`` of themselves (a lens too strong for the
    fixed-point iteration, k1 = 1e6 say, makes it diverge)."""
    angles = np.linspace(0.0, 2 * np.pi, 8, endpoint=False)
    radii = np.linspace(0.0, corner, 41)
    points = np.stack(
        np.broadcast_arrays(np.outer(radii, np.cos(angles)), np.outer(radii, np.sin(angles))), -1
    )
    with np.errstate(all="ignore"):
        back = distort(undistort(points, dist), dist)
    return bool(np.all(np.abs(back - points) <= tolerance))


@compiled
def _undistorted(
    xy_d: np.ndarray, k1: float, k2: float, p1: float, p2: float, k3: float, iterations: int
) -> np.ndarray:
    """:func:`undistort` of points (N, 2), each iterated until it is a fixed point to the bit
    (every further iteration would return it unchanged) or ``iterations`` are done."""
    xy = xy_d.copy()
    for i in range(xy.shape[0]):
        x_d, y_d = xy_d[i, 0], xy_d[i, 1]
        x, y = x_d, y_d
        for _ in range(iterations):
            r2 = x * x + y * y
            radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
            dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
            dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
            x_new, y_new = (x_d - dx) / radial, (y_d - dy) / radial
            if _same_bits(x_new, x) and _same_bits(y_new, y):
                break
            x, y = x_new, y_new
        xy[i, 0], xy[i, 1] = x, y
    return xy


@compiled
def _same_bits(a: float, b: float) -> bool:
    """Whether ``a`` and ``b`` are the same float to the bit (``-0.0`` is not ``0.0``; a NaN
    is itself, as the iteration carries it)."""
    return (a == b and math.copysign(1.0, a) == math.copysign(1.0, b)) or (a != a and b != b)


@dataclass(frozen=True, eq=False)
class CameraCalibration:
    """Intrinsics ``K`` (3x3) and distortion ``dist`` (``k1 k2 p1 p2 k3``) of a camera."""

    K: np.ndarray
    dist: np.ndarray

    @functools.cached_property
    def distorted(self) -> bool:
        """Whether the lens distorts (any coefficient non-zero); computed once."""
        return bool(np.any(self.dist != 0))

    def to_pixels(self, xy: np.ndarray) -> np.ndarray:
        """Pixels (..., 2) of undistorted normalised coordinates (..., 2)."""
        d = distort(xy, self.dist) if self.distorted else xy
        return d @ self.K[:2, :2].T + self.K[:2, 2]

    @functools.cached_property
    def _pixels_to_normalised(self) -> np.ndarray:
        """The transpose of ``K[:2, :2]``'s inverse (pixels to normalised), computed once."""
        return np.linalg.inv(self.K[:2, :2]).T

    def to_normalised(self, uv: np.ndarray) -> np.ndarray:
        """Undistorted normalised coordinates of pixels (..., 2)."""
        d = (np.asarray(uv, float) - self.K[:2, 2]) @ self._pixels_to_normalised
        return undistort(d, self.dist) if self.distorted else d

    def undistort_pixels(self, uv: np.ndarray) -> np.ndarray:
        """Where pixels (..., 2) would lie through ``K`` without the lens's distortion."""
        if not self.distorted:
            return np.asarray(uv, float)
        return self.to_normalised(uv) @ self.K[:2, :2].T + self.K[:2, 2]

    def project(self, camera_points: np.ndarray) -> np.ndarray:
        """Pixels (N, 2) of points (N, 3) in camera coordinates; points behind give NaN."""
        points = np.asarray(camera_points, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            xy = points[:, :2] / points[:, 2:3]
        uv = self.to_pixels(xy)
        uv[points[:, 2] <= 0] = np.nan
        return uv


#: A position on the robot along its x or y axis (m).
RobotOffset = Annotated[float, Range(ge=-ROBOT_EXTENT_M, le=ROBOT_EXTENT_M)]


def pose_matrix(x: float, y: float, z: float, rotation: np.ndarray) -> np.ndarray:
    """The 4x4 pose of ``rotation`` (3x3) at ``(x, y, z)``."""
    pose = np.eye(4)
    pose[:3, :3] = rotation
    pose[:3, 3] = (x, y, z)
    return pose


def rot_z(angle: float) -> np.ndarray:
    """Rotation matrix (3x3) by ``angle`` (rad) about z."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rot_y(angle: float) -> np.ndarray:
    """Rotation matrix (3x3) by ``angle`` (rad) about y."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@dataclass(frozen=True)
class PanTiltMount:
    """A camera on a pan-tilt head at ``(x, y, z)`` in the robot frame (on the floor below the
    axle midpoint, x forward, z up): ``mount(pan, tilt)`` is the nominal robot-from-camera 4x4
    (OpenCV axes) for the mount angles (rad; pan about z, positive left; tilt positive up).
    A fixed camera looking ahead is the mount at ``pan = tilt = 0``."""

    x: RobotOffset
    y: RobotOffset
    z: RobotLength  # above the floor

    def __call__(self, pan: float, tilt: float) -> np.ndarray:
        rotation = rot_z(pan) @ rot_y(-tilt) @ LINK_FROM_OPTICAL
        return pose_matrix(self.x, self.y, self.z, rotation)
