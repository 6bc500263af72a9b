"""From a detected landmark board to its pose in the robot frame, with covariance.

The board's pose relative to the camera comes from the known square layout (planar PnP,
OpenCV's IPPE); its covariance from the Gauss-Newton normal matrix of the reprojection,
``sigma_px^2 (J^T J)^-1``. Mapped into the robot frame through the mount kinematics, the
measurement is ``z = [x, y, phi]``: the board centre on the floor plane and the yaw of its
outward normal, the SE(2) pose of the landmark relative to the robot.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from stsf_gym.estimators.base import MapLandmark, SensorModel
from stsf_gym.geometry import compose, compose_jacobians, inverse, inverse_jacobian
from stsf_gym.vision.landmarks import square_centres


@dataclass(frozen=True)
class LandmarkObservation:
    """One detected map landmark in one frame."""

    landmark: MapLandmark
    indices: np.ndarray  # square indices (square_centres order)
    image_points: np.ndarray  # (N, 2) pixels
    robot_from_camera: np.ndarray  # 4x4, nominal mount kinematics at the frame's pan/tilt
    z: np.ndarray  # [x, y, phi]: landmark pose in the robot frame
    pnp_params: np.ndarray  # [rvec, tvec]: the board's pose in the camera (solvePnP)
    pnp_cov: np.ndarray  # 6x6 covariance of pnp_params, sigma_px^2 (J^T J)^-1

    @classmethod
    def given(
        cls,
        landmark: MapLandmark,
        indices: np.ndarray,
        image_points: np.ndarray,
        robot_from_camera: np.ndarray,
        z: np.ndarray,
        cov: np.ndarray,
    ) -> LandmarkObservation:
        """An observation with ``z`` and its covariance given (a synthetic measurement)."""
        observation = cls(
            landmark, indices, image_points, robot_from_camera, z, np.zeros(6), np.zeros((6, 6))
        )
        observation.__dict__["cov"] = cov  # where functools.cached_property keeps its value
        return observation

    @functools.cached_property
    def cov(self) -> np.ndarray:
        """3x3 covariance of ``z``: ``pnp_cov`` through z's Jacobian by the PnP parameters,
        made when first asked for (most frames' observations serve only their ``z``)."""
        G = _board_pose_jacobian(self.pnp_params, self.robot_from_camera)
        cov = G @ self.pnp_cov @ G.T
        return (cov + cov.T) / 2

    def by_camera(self) -> np.ndarray:
        """Jacobian (3, 2) of ``z`` by the considered camera errors ``[theta, s]``.

        The believed principal point off by ``theta f`` pixels (horizontally) shifts every
        undistorted point by ``-theta`` in normalised x: the board moves by ``-Z theta`` along
        the camera's x axis (``Z`` its depth) and its orientation turns by ``theta``. The
        believed focal length off by a factor ``1 + s`` scales the depth by it (from the
        board's size or a motion-stereo disparity alike) and leaves the lateral offset."""
        rotation, origin = self.robot_from_camera[:2, :3], self.robot_from_camera[:2, 3]
        axis, right = rotation[:, 2], rotation[:, 0]
        depth = float((self.z[:2] - origin) @ axis)
        return np.array([[*(-depth * right), 1.0], [*(depth * axis), 0.0]]).T

    @property
    def range_bearing(self) -> np.ndarray:
        """[range, bearing] of the board centre from the robot origin."""
        return np.array([math.hypot(self.z[0], self.z[1]), math.atan2(self.z[1], self.z[0])])


def _board_pose(params: np.ndarray, robot_from_camera: np.ndarray) -> np.ndarray:
    """z = [x, y, phi] from PnP parameters (rvec, tvec) of camera-from-board."""
    rotation, _ = cv2.Rodrigues(params[:3])
    return np.array(
        [*_board_centre(params[3:], robot_from_camera), _board_yaw(rotation, robot_from_camera)]
    )


def _board_centre(tvec: np.ndarray, robot_from_camera: np.ndarray) -> np.ndarray:
    """[x, y] of the board centre in the robot frame, from camera-from-board ``tvec``."""
    return (robot_from_camera[:3, :3] @ tvec + robot_from_camera[:3, 3])[:2]


def _board_yaw(rotation: np.ndarray, robot_from_camera: np.ndarray) -> float:
    """Yaw in the robot frame of the board's z axis (out of the board), from camera-from-board
    ``rotation``."""
    normal = robot_from_camera[:3, :3] @ rotation[:, 2]
    return math.atan2(normal[1], normal[0])


def _board_pose_jacobian(params: np.ndarray, robot_from_camera: np.ndarray) -> np.ndarray:
    """dz/dparams (3, 6) of :func:`_board_pose` by central differences of 1e-6: the rotation
    ``params[:3]`` moves only the yaw, the translation ``params[3:]`` only the centre, so each
    difference evaluates only the part that moves (the other's difference is exactly 0)."""
    G = np.zeros((3, 6))
    for i in range(3):
        ahead, behind = params[:3].copy(), params[:3].copy()
        ahead[i] += 1e-6
        behind[i] -= 1e-6
        yaw_ahead = _board_yaw(cv2.Rodrigues(ahead)[0], robot_from_camera)
        yaw_behind = _board_yaw(cv2.Rodrigues(behind)[0], robot_from_camera)
        G[2, i] = math.remainder(yaw_ahead - yaw_behind, math.tau) / 2e-6
        ahead, behind = params[3:].copy(), params[3:].copy()
        ahead[i] += 1e-6
        behind[i] -= 1e-6
        diff = _board_centre(ahead, robot_from_camera) - _board_centre(behind, robot_from_camera)
        G[:2, 3 + i] = diff / 2e-6
    return G


def observe(
    detection, model: SensorModel, pan: float, tilt: float, sigma_px: float
) -> LandmarkObservation | None:
    """The observation of a detection, or ``None`` for an unknown id or a failed fit."""
    landmark = model.landmarks.get(detection.landmark_id)
    if landmark is None or len(detection.indices) < 4:
        return None
    plane = square_centres(detection.landmark_id, model.pattern)[detection.indices]
    object_points = np.column_stack([plane, np.zeros(len(plane))])
    image_points = np.asarray(detection.image_points, dtype=np.float64)
    ok, rvec, tvec = cv2.solvePnP(
        object_points, image_points, model.camera_matrix, None, flags=cv2.SOLVEPNP_IPPE
    )
    if not ok or tvec[2, 0] <= 0:
        return None
    params = np.concatenate([rvec.ravel(), tvec.ravel()])
    _, jac = cv2.projectPoints(object_points, rvec, tvec, model.camera_matrix, None)
    normal_matrix = jac[:, :6].T @ jac[:, :6]
    try:
        params_cov = sigma_px**2 * np.linalg.inv(normal_matrix)
    except np.linalg.LinAlgError:
        return None
    robot_from_camera = model.robot_from_camera(pan, tilt)
    return LandmarkObservation(
        landmark,
        np.asarray(detection.indices),
        image_points,
        robot_from_camera,
        _board_pose(params, robot_from_camera),
        params,
        params_cov,
    )


def landmark_world_pose(landmark: MapLandmark) -> np.ndarray:
    """The map landmark as an SE(2) pose: board centre and the yaw of its outward normal."""
    return np.array(
        [landmark.centre[0], landmark.centre[1], math.atan2(landmark.normal[1], landmark.normal[0])]
    )


def robot_pose_jacobian(landmark: MapLandmark, z: np.ndarray) -> np.ndarray:
    """The Jacobian of :func:`robot_pose_from_landmark`'s pose by ``z``."""
    _, j_b = compose_jacobians(landmark_world_pose(landmark), inverse(z))
    return j_b @ inverse_jacobian(z)


def robot_pose_from_landmark(
    landmark: MapLandmark, z: np.ndarray, cov: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The robot's world pose, and its covariance, from the landmark's pose ``z`` relative to
    the robot (covariance ``cov``) and the landmark's map pose: ``map (+) (-) z``."""
    jac = robot_pose_jacobian(landmark, z)
    return compose(landmark_world_pose(landmark), inverse(z)), jac @ cov @ jac.T
