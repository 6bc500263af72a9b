"""What a factor graph of one episode is made of: odometry legs between camera frames and
landmark poses, with the considered parameters the EKF carries (:mod:`..pose_errors`).

**Considered parameters** ``k = [c; m; theta, s]`` (7): the relative errors of the left and
right wheel radius and the wheelbase (``c``,
:class:`~stsf_gym.estimators.odometry_model.OdometryNoise`), the camera mount's position error
``m`` and the believed camera calibration's heading
``theta`` and focal scale ``s``. One draw per episode, the same in every leg and every frame:
the smoothers estimate ``k`` as a variable with the prior ``N(0, Sigma_k)`` instead of treating
its effect as white noise, which would average a systematic error away.

**Odometry leg** from frame ``i`` to frame ``j``: the steps' mid-point increments
(:func:`~stsf_gym.estimators.odometry_model.odometry_step` from the origin) composed in frame ``i``,
``Delta = delta_1 (+) ... (+) delta_n``, with the first-order covariance of the slip ``Q`` and the
Jacobian ``J_c`` by ``c``, both carried through the composition (a preintegration)::

    Q <- A Q A^T + B G N G^T B^T,   J_c <- A J_c + B G_c
    (A, B) = d(Delta (+) delta) / d(Delta, delta)

so the true leg is ``Delta - J_c c`` to first order (a believed radius ``1 + c`` too large
reports ``d c`` too much travel).

**Landmark pose** ``z = [x, y, phi]`` of a map board in the robot frame
(:class:`~stsf_gym.estimators.landmark_observation.LandmarkObservation`), predicted by
``h(x) = (-) x (+) L``, with ``z = h(x) + M k + v``: ``M = [0, -I_2 (mount), dz/d(theta, s)]``
and ``v ~ N(0, R)``, ``R`` the PnP covariance at ``sigma_px`` plus floors for the errors PnP's
first-order covariance leaves out (as the EKF's): ``position_std_floor`` and
``position_std_per_m`` times the range in x and y, ``orientation_std_floor`` on ``phi``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from stsf_gym.estimators.base import SensorModel
from stsf_gym.estimators.landmark_observation import (
    LandmarkObservation,
    landmark_world_pose,
)
from stsf_gym.estimators.odometry_model import odometry_step
from stsf_gym.geometry import compose, compose_jacobians, inverse, wrap_angle

CONSIDERED = 7  # wheel radii and wheelbase (3), mount (2), camera heading and focal scale (2)
LEG_VARIANCE_FLOOR = 1e-8  # m^2 and rad^2 added to every leg's slip covariance (0.1 mm, mrad)


def considered_cov(model: SensorModel, mount_std: float) -> np.ndarray:
    """``Sigma_k``: the prior covariance of the considered parameters."""
    cov = np.zeros((CONSIDERED, CONSIDERED))
    cov[:3, :3] = model.odometry_noise.calibration_cov
    cov[3:5, 3:5] = np.eye(2) * mount_std**2
    cov[5:, 5:] = np.diag(np.square(model.camera_calibration_std))
    return cov + np.eye(CONSIDERED) * 1e-12  # a nil prior (no calibration error) stays invertible


@dataclass
class OdometryLeg:
    """The preintegrated wheel odometry since a frame: ``delta`` (in that frame), the slip's
    covariance ``cov`` and ``by_calibration`` = ``J_c`` (3 x 3)."""

    delta: np.ndarray = field(default_factory=lambda: np.zeros(3))
    cov: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    by_calibration: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))

    def add(self, model: SensorModel, d_left: float, d_right: float) -> None:
        """Compose one step's wheel travels (m) onto the leg."""
        step, _, G, G_c = odometry_step(np.zeros(3), d_left, d_right, model.calibration.wheelbase)
        slip = model.odometry_noise.slip_cov(d_left, d_right)
        A, B = compose_jacobians(self.delta, step)
        self.delta = compose(self.delta, step)
        self.cov = A @ self.cov @ A.T + B @ G @ slip @ G.T @ B.T
        self.by_calibration = A @ self.by_calibration + B @ G_c

    def noise(self) -> np.ndarray:
        """The slip covariance plus :data:`LEG_VARIANCE_FLOOR`: the mid-point model puts almost
        no sideways error in a short leg (1e-10 m^2 in 2.4 cm), which would make a leg a
        million times stiffer than a weak prior beside it and its elimination ill-posed."""
        return self.cov + np.eye(3) * LEG_VARIANCE_FLOOR


@dataclass(frozen=True)
class LandmarkPose:
    """One map board seen in one frame: ``z``, its noise ``R`` and ``M = dz/dk``."""

    landmark_pose: np.ndarray  # the board's map pose [x, y, yaw of its normal]
    z: np.ndarray
    noise: np.ndarray
    by_considered: np.ndarray  # (3, CONSIDERED)

    @property
    def range(self) -> float:
        return float(np.hypot(*self.z[:2]))

    def predicted(self, pose: np.ndarray) -> np.ndarray:
        """``h(x) = (-) x (+) L``: the board's pose seen from robot pose ``x``."""
        return compose(inverse(pose), self.landmark_pose)

    def robot_pose(self) -> np.ndarray:
        """The robot pose this measurement alone gives (``M k`` = 0): ``L (+) (-) z``."""
        return compose(self.landmark_pose, inverse(self.z))

    def residual(self, pose: np.ndarray, considered: np.ndarray) -> np.ndarray:
        """``h(x) + M k - z``, heading wrapped."""
        error = self.predicted(pose) + self.by_considered @ considered - self.z
        error[2] = wrap_angle(error[2])
        return error

    def by_pose(self, pose: np.ndarray) -> np.ndarray:
        """``dh/dx`` for a perturbation of ``x`` in its own frame (GTSAM's Pose2 retraction)."""
        seen = self.predicted(pose)
        return np.array([[-1.0, 0.0, seen[1]], [0.0, -1.0, -seen[0]], [0.0, 0.0, -1.0]])


def landmark_pose(
    observation: LandmarkObservation,
    position_std_floor: float,
    position_std_per_m: float,
    orientation_std_floor: float,
) -> LandmarkPose:
    """The graph's measurement of an observation, with the floors on its noise."""
    z = observation.z
    position_var = position_std_floor**2 + (position_std_per_m * float(np.hypot(*z[:2]))) ** 2
    noise = observation.cov + np.diag([position_var, position_var, orientation_std_floor**2])
    by_considered = np.zeros((3, CONSIDERED))
    by_considered[:2, 3:5] = -np.eye(2)  # a mount m off puts the board -m off
    by_considered[:, 5:] = observation.by_camera()
    return LandmarkPose(
        landmark_world_pose(observation.landmark), z.copy(), (noise + noise.T) / 2, by_considered
    )
