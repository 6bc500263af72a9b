"""Motion stereo between two frames of the moving camera, with the camera motion from odometry.

Wraps :func:`stsf_gym.fusion.motion_stereo_range` (eq. 8-20) for matched landmark squares:
builds the image rays (:func:`matched_rays`), takes the relative camera pose the robot
believes, and turns the odometry covariance of that motion into the baseline and rotation
covariances of :func:`stsf_gym.fusion.motion_stereo_variance`.
"""

from __future__ import annotations

import numpy as np

from stsf_gym.fusion import DegenerateGeometryError, motion_stereo_estimate, motion_stereo_range
from stsf_gym.fusion.motion_stereo import motion_stereo_ranges


def matched_rays(
    points_prev: dict[int, np.ndarray],
    points_curr: dict[int, np.ndarray],
    camera_matrix: np.ndarray,
    min_points: int = 4,
) -> tuple[np.ndarray, np.ndarray] | None:
    """The image rays ``[u - c_x, v - c_y, f]`` (N, 3) in frames k-1 and k of the squares seen
    in both (``points_*``: pixel of each square index), in index order; ``None`` when fewer
    than ``min_points`` match."""
    common = sorted(points_prev.keys() & points_curr.keys())
    if len(common) < min_points:
        return None
    f, centre = camera_matrix[0, 0], camera_matrix[:2, 2]

    def rays(points: dict[int, np.ndarray]) -> np.ndarray:
        uv = np.array([points[i] for i in common]) - centre
        return np.column_stack([uv, np.full(len(common), f)])

    return rays(points_prev), rays(points_curr)


def pair_range(
    rays: tuple[np.ndarray, np.ndarray],
    prev_from_curr: np.ndarray,
    normal: np.ndarray,
    motion_cov: np.ndarray | None,
    camera_from_robot: np.ndarray,
    sigma_px: float,
) -> tuple[float, float] | None:
    """Plane distance ``D`` from camera k and its variance (0 without ``motion_cov``: ``D``
    alone is wanted), or ``None`` when not measurable.

    Args:
        rays: :func:`matched_rays` of frames k-1 and k.
        prev_from_curr: 4x4 pose of camera k in camera k-1 (``X_prev = R X_k + t``).
        normal: unit plane normal in camera-k axes, pointing towards the plane.
        motion_cov: 3x3 odometry covariance of the robot motion [x, y, yaw] between frames.
        camera_from_robot: 3x3 rotation from robot to camera-k axes (robot z is the turn axis).
    """
    q_prev, q_curr = rays
    R, t = prev_from_curr[:3, :3], prev_from_curr[:3, 3]
    if motion_cov is None:
        try:
            return motion_stereo_range(q_prev, q_curr, R, t, normal), 0.0
        except DegenerateGeometryError:
            return None
    cov_xy = np.zeros((3, 3))
    cov_xy[:2, :2] = motion_cov[:2, :2]
    cov_t = camera_from_robot @ cov_xy @ camera_from_robot.T
    axis = camera_from_robot[:, 2]
    cov_rot = motion_cov[2, 2] * np.outer(axis, axis)
    try:
        return motion_stereo_estimate(q_prev, q_curr, R, t, normal, sigma_px, cov_t, cov_rot)
    except DegenerateGeometryError:
        return None


def pair_ranges(
    rays: tuple[np.ndarray, np.ndarray], prevs_from_curr: list[np.ndarray], normal: np.ndarray
) -> list[float | None]:
    """:func:`pair_range`'s ``D`` alone (no ``motion_cov``) for each of several poses of camera
    k in camera k-1, ``None`` where not measurable: the rays are checked once."""
    motions = [(pose[:3, :3], pose[:3, 3]) for pose in prevs_from_curr]
    return motion_stereo_ranges(*rays, motions, normal)
