"""The GTSAM factors of :mod:`.measurements`: poses ``x_i`` (``Pose2``), the considered
parameters ``k`` (a 7-vector) and two custom factors, each with its analytic Jacobians.

**Odometry** between frames ``i`` and ``j`` with leg ``Delta``, ``J_c`` and slip covariance
``Q``: with ``d = R_i^T (t_j - t_i)`` and ``phi = theta_j - theta_i`` (``x_j`` in frame ``i``)::

    e = [d; phi] - (Delta - J_c c),   e ~ N(0, Q)
    de/dx_i = [[-I, (d_y, -d_x)^T], [0, -1]],  de/dx_j = [[R(phi), 0], [0, 1]],  de/dc = J_c

**Landmark**: ``e = h(x) + M k - z ~ N(0, R)``, ``de/dx = dh/dx``, ``de/dk = M``
(:class:`~.measurements.LandmarkPose`). Jacobians by a pose are for GTSAM's ``Pose2`` retraction
(a perturbation in the pose's own frame).
"""

from __future__ import annotations

import gtsam
import numpy as np

from stsf_gym.estimators.references.measurements import LandmarkPose, OdometryLeg
from stsf_gym.geometry import rot2, wrap_angle

CONSIDERED_KEY = gtsam.symbol("k", 0)


def pose_key(index: int) -> int:
    """The GTSAM key of pose ``index``."""
    return gtsam.symbol("x", index)


def as_pose2(pose: np.ndarray) -> gtsam.Pose2:
    """``[x, y, yaw]`` as a ``gtsam.Pose2``."""
    return gtsam.Pose2(float(pose[0]), float(pose[1]), float(pose[2]))


def as_array(pose: gtsam.Pose2) -> np.ndarray:
    """A ``gtsam.Pose2`` as ``[x, y, yaw]``."""
    return np.array([pose.x(), pose.y(), pose.theta()])


def gaussian(cov: np.ndarray) -> gtsam.noiseModel.Gaussian:
    """A GTSAM Gaussian noise model of covariance ``cov``."""
    return gtsam.noiseModel.Gaussian.Covariance(np.ascontiguousarray(cov, dtype=float))


def world_to_local_cov(pose: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """A pose covariance in world axes as GTSAM's ``Pose2`` tangent (its own frame) holds it."""
    rotation = np.eye(3)
    rotation[:2, :2] = rot2(pose[2]).T
    return rotation @ cov @ rotation.T


def local_to_world_cov(pose: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """:func:`world_to_local_cov`'s inverse: the ``pose_cov`` every estimator reports."""
    rotation = np.eye(3)
    rotation[:2, :2] = rot2(pose[2])
    return rotation @ cov @ rotation.T


def pose_prior(index: int, pose: np.ndarray, cov: np.ndarray) -> gtsam.PriorFactorPose2:
    """A prior on pose ``index`` at ``pose`` with covariance ``cov`` in world axes."""
    return gtsam.PriorFactorPose2(
        pose_key(index), as_pose2(pose), gaussian(world_to_local_cov(pose, cov))
    )


def considered_prior(mean: np.ndarray, cov: np.ndarray) -> gtsam.PriorFactorVector:
    """The prior (``mean``, ``cov``) on the considered parameters ``k``."""
    return gtsam.PriorFactorVector(CONSIDERED_KEY, np.asarray(mean, float), gaussian(cov))


def odometry_factor(i: int, j: int, leg: OdometryLeg) -> gtsam.CustomFactor:
    """The factor between poses ``i`` and ``j``: the preintegrated ``leg``'s ``Delta`` with its slip
    covariance, corrected by the calibration ``c`` through its Jacobian (analytic Jacobians).
    """
    delta, by_calibration = leg.delta.copy(), leg.by_calibration.copy()

    def error(factor, values, jacobians):
        xi, xj = values.atPose2(pose_key(i)), values.atPose2(pose_key(j))
        c = values.atVector(CONSIDERED_KEY)[:3]
        rotation = rot2(xi.theta())
        d = rotation.T @ np.array([xj.x() - xi.x(), xj.y() - xi.y()])
        phi = xj.theta() - xi.theta()
        e = np.array([*d, phi]) - (delta - by_calibration @ c)
        e[2] = wrap_angle(e[2])
        if jacobians is not None:
            jacobians[0] = np.array([[-1.0, 0.0, d[1]], [0.0, -1.0, -d[0]], [0.0, 0.0, -1.0]])
            by_j = np.eye(3)
            by_j[:2, :2] = rot2(phi)
            jacobians[1] = by_j
            by_k = np.zeros((3, len(values.atVector(CONSIDERED_KEY))))
            by_k[:, :3] = by_calibration
            jacobians[2] = by_k
        return e

    return gtsam.CustomFactor(
        gaussian(leg.noise()), [pose_key(i), pose_key(j), CONSIDERED_KEY], error
    )


def landmark_factor(index: int, measurement: LandmarkPose) -> gtsam.CustomFactor:
    """The factor of one board's PnP pose on pose ``index``: ``z = h(x) + M k + v`` (analytic
    Jacobians).
    """

    def error(factor, values, jacobians):
        pose = as_array(values.atPose2(pose_key(index)))
        k = values.atVector(CONSIDERED_KEY)
        if jacobians is not None:
            jacobians[0] = measurement.by_pose(pose)
            jacobians[1] = measurement.by_considered
        return measurement.residual(pose, k)

    return gtsam.CustomFactor(gaussian(measurement.noise), [pose_key(index), CONSIDERED_KEY], error)
