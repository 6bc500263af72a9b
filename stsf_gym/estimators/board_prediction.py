"""Where a tracked landmark's board must appear in the next frame: track-aided matching's input.

A landmark track holds the board's pose relative to the robot at its last frame,
``z = [x, y, phi]``, and the odometry since. Carried to now (eq. 3: ``(-) motion (+) z``), it
places the board relative to the robot; the mount kinematics at the frame's pan and tilt and
the camera the robot believes it has (K and distortion) put its four corners in the image,
which gives the position and the size the matcher searches at
(:class:`~stsf_gym.vision.predicted.BoardPrediction`). Only the track and the map's board
geometry enter, never the pose estimate: the prediction is the track's own.
"""

from __future__ import annotations

import numpy as np

from stsf_gym.camera_model import CameraCalibration
from stsf_gym.estimators.base import MapLandmark, SensorModel
from stsf_gym.geometry import compose, inverse
from stsf_gym.vision.landmarks import board_corners, square_centres
from stsf_gym.vision.predicted import BoardPrediction


def board_axes(landmark: MapLandmark, model: SensorModel) -> np.ndarray:
    """(2, 3) world directions of the landmark plane's x (right) and y (up) axes, from the
    map's square centres (least squares over ``world - centre = plane @ axes``)."""
    plane = square_centres(landmark.id, model.pattern)
    axes, *_ = np.linalg.lstsq(plane, landmark.square_centres - landmark.centre, rcond=None)
    return axes


def board_outline(landmark: MapLandmark, model: SensorModel) -> tuple[np.ndarray, np.ndarray]:
    """The board's four corners in its own frame (x along the outward normal, y to its left):
    their (4, 2) floor coordinates and (4,) heights; fixed for a map, so computed once."""
    axes = board_axes(landmark, model)
    yaw = np.arctan2(landmark.normal[1], landmark.normal[0])
    to_local = np.array([[np.cos(yaw), np.sin(yaw), 0.0], [-np.sin(yaw), np.cos(yaw), 0.0]])
    corners = board_corners(model.pattern) @ axes  # (4, 3) world offsets from the centre
    return corners @ to_local.T, corners[:, 2] + landmark.centre[2]


def predict_board(
    landmark_id: int,
    outline: tuple[np.ndarray, np.ndarray],
    z_then: np.ndarray,
    motion: np.ndarray,
    camera_from_robot: np.ndarray,
    calibration: CameraCalibration,
    search_px: float,
) -> BoardPrediction | None:
    """The board of ``landmark_id`` (its :func:`board_outline`) measured at ``z_then`` (robot
    frame), after the robot moved by ``motion`` (odometry, pose of now in the frame then),
    seen through ``calibration`` from ``camera_from_robot`` (4x4); None when it is behind the
    camera."""
    z_now = compose(inverse(motion), np.asarray(z_then, dtype=float))
    local_xy, height = outline
    c, s = np.cos(z_now[2]), np.sin(z_now[2])
    robot_xy = local_xy @ np.array([[c, s], [-s, c]]) + z_now[:2]
    robot = np.column_stack([robot_xy, height, np.ones(4)])
    camera = (camera_from_robot @ robot.T).T[:, :3]
    if (camera[:, 2] <= 0.05).any():
        return None
    return BoardPrediction(landmark_id, calibration.project(camera), search_px)
