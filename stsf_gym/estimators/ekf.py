"""The modern reference: an extended Kalman filter on landmark range and bearing.

**State.** The robot pose ``x = [x, y, yaw]`` (world frame, yaw kept in ``(-pi, pi]``) with
covariance ``P``. The landmark map (:attr:`SensorModel.landmarks`) is known, not estimated.

**Prediction** (every step). The odometry estimator's mid-point model,
:meth:`OdometryEstimator.predict`: ``x <- f(x, d_l, d_r)``, ``P <- F P F^T + G N G^T`` for the
slip ``N``, plus the unknown calibration errors ``c`` carried as considered parameters
(:mod:`stsf_gym.estimators.pose_errors`): ``P`` keeps its correlation with ``c``, so the
drift they cause is predicted as the linear growth it is (see below).

**Measurement** (every new camera frame). The detector finds the boards; each board of the map
becomes a :class:`LandmarkObservation` whose ``z[:2] = (u, v)`` is the board centre in the
robot frame, with covariance ``C`` from the PnP normal matrix at ``sigma_px``. The filter uses
its range and bearing::

    z = [r, b] = [sqrt(u^2 + v^2), atan2(v, u)]
    R = J C J^T + diag(range_std_floor^2 + (range_std_fraction r)^2, bearing_std_floor^2)
    J = [[u / r, v / r], [-v / r^2, u / r^2]]

and predicts it from the pose and the map centre ``(l_x, l_y)``: with ``dx = l_x - x``,
``dy = l_y - y``, ``q = dx^2 + dy^2``::

    h(x) = [sqrt(q), atan2(dy, dx) - yaw]
    H = [[-dx / sqrt(q), -dy / sqrt(q), 0], [dy / q, -dx / q, -1]]

**Update.** Innovation ``nu = z - h(x)`` with its bearing wrapped to ``(-pi, pi]``,
``S = H P H^T + R``, gain ``K = P H^T S^-1``, ``x <- x + K nu`` (yaw wrapped), and the
covariance in Joseph form::

    P <- (I - K H) P (I - K H)^T + K R K^T

a sum of two positive semi-definite terms, so ``P`` stays symmetric positive definite under
round-off, and the right covariance for *any* gain, not only the optimal one (the short form
``(I - K H) P`` is exact only for the optimal gain and can lose definiteness). The
cross-covariance with ``c`` becomes ``(I - K H) P_xc``: ``c`` is not estimated (a Schmidt
update), so the EKF stays the textbook one and only its covariance knows the calibration.

**Gating.** Before it touches the state, a measurement is rejected when its Mahalanobis
distance ``d^2 = nu^T S^-1 nu`` exceeds the chi-square quantile of ``gate_probability`` with 2
degrees of freedom (``-2 ln(1 - p)``, 9.21 for 0.99): a misread id, a bad PnP fit. Boards
outside ``[min_range, max_range]`` are not used. ``counters``: ``frames``, ``detections``,
``landmark_updates``, ``gated_out``, ``out_of_range``, ``unusable`` (no valid observation),
``relocalised``.

**Re-localisation.** A gate cannot tell a wrong detection from a wrong estimate: after a kidnap
it would reject every landmark for good. Each rejected board's PnP pose gives the robot's full
pose through the map; when ``relocalise_after`` rejected ones in a row agree, the state restarts
there with their covariance times ``relocalise_inflation``
(:mod:`stsf_gym.estimators.relocalise`). The EKF sees a board in every frame, so it needs more
of them in a row than the pair-based estimators do.

**Why the covariance stays consistent.** The measurement covariance is the first-order
propagation of the pixel noise through PnP and the range/bearing map, and the prediction that
of the wheel noise; both models leave out errors that are *systematic*, and a Kalman filter
that treats systematic errors as white averages them away and becomes overconfident:

- the mount kinematics and camera intrinsics are nominal and the square centroids have a small
  bias, so the range of a distant board is off by a fraction of a percent, and at 5 Hz
  consecutive frames of one board share most of that error. The floors
  (``range_std_floor``, ``range_std_fraction``, ``bearing_std_floor``) bound the information
  one frame can carry; a conservative ``sigma_px`` does the same where pixel noise dominates;
- the per-episode wheel-radius and wheelbase calibration errors make the odometry drift
  *linearly* with distance, which a random-walk noise model (all a per-step model can be)
  matches at one distance only: too wide over a short gap, too narrow over a long one, and
  blind to the drift always going the same way. Carried as considered parameters, they keep
  the predicted drift right over any gap, and the repeated measurements cannot shrink ``P``
  below the error the calibration leaves.

The Joseph form and the gate keep single updates from breaking ``P``; the average NEES against
the true pose (``tests/estimators/test_ekf.py``) checks the whole.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from stsf_gym.estimators.base import MapLandmark, SensorModel, chi_square_gate
from stsf_gym.estimators.frame_detector import FrameDetector
from stsf_gym.estimators.landmark_observation import (
    LandmarkObservation,
    observe,
    robot_pose_from_landmark,
)
from stsf_gym.estimators.odometry_estimator import OdometryEstimator
from stsf_gym.estimators.relocalise import Relocaliser
from stsf_gym.estimators.settings import EKFSettings
from stsf_gym.geometry import wrap_angle


class EKFEstimator(OdometryEstimator):
    """Odometry prediction, then one range/bearing EKF update per map landmark seen.

    Settings (:class:`EKFSettings`, ``configs/estimators/ekf.yaml``):
        sigma_px: pixel noise of the square centres assumed for the observation covariance.
        gate_probability: Mahalanobis gate, the chi-square (2 dof) probability kept.
        min_range, max_range: boards outside this range (m) from the robot are not used.
        range_std_floor: standard deviation (m) added to every range measurement,
        range_std_fraction: and this fraction of the range (added in quadrature).
        bearing_std_floor: standard deviation (rad) added to every bearing measurement.
        mount_std: standard deviation (m) of the camera mount's unknown position error on the
            robot, in x and y: one error for every frame, a considered parameter
            (:mod:`~stsf_gym.estimators.pose_errors`).
        relocalise_after: rejected boards in a row that must agree to re-localise (0: never).
        relocalise_inflation: factor on their covariance for the restarted state.
    """

    sensors = ("encoders", "camera")

    name = "ekf"
    settings_type: ClassVar[type] = EKFSettings

    def __init__(self, settings: EKFSettings) -> None:
        super().__init__(settings)
        s = settings
        self.sigma_px, self.gate_probability = s.sigma_px, s.gate_probability
        self.gate = chi_square_gate(s.gate_probability, dof=2)
        self.min_range, self.max_range = s.min_range, s.max_range
        self.range_std_floor, self.range_std_fraction = s.range_std_floor, s.range_std_fraction
        self.bearing_std_floor = s.bearing_std_floor
        self.relocaliser = Relocaliser(
            s.relocalise_after, s.relocalise_inflation, chi_square_gate(s.gate_probability, dof=3)
        )

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        super().reset(model, initial_pose, initial_cov)
        self.detector = FrameDetector(model.pattern, set(model.landmarks), model.camera_calibration)
        self.relocaliser.clear()

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        with self.timed("odometry"):
            self.predict(obs)
            self.mean[2] = wrap_angle(self.mean[2])
        if int(obs["image_new"]):
            self.counters["frames"] += 1
            with self.timed("detect"):
                detections = self.detector(obs)
            with self.timed("update"):
                pan, tilt = (float(a) for a in obs["camera_pan_tilt"])
                self.counters["frames_matched"] += bool(detections)  # the detector keeps map ids
                for detection in detections:
                    self.counters["detections"] += 1
                    observation = observe(detection, self.model, pan, tilt, self.sigma_px)
                    if observation is None:
                        self.counters["unusable"] += 1
                    else:
                        self.correct(observation)
        return self.mean, self.cov

    def measurement(
        self, observation: LandmarkObservation
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``z = [range, bearing]`` of the board centre, its covariance ``R`` (with floors) and
        its Jacobian by the considered parameters: a camera mounted ``m`` off puts the centre
        ``-m`` off in the robot frame; the camera's calibration errors move it as
        :meth:`LandmarkObservation.by_camera` says."""
        u, v = observation.z[:2]
        q = u * u + v * v
        r = math.sqrt(q)
        J = np.array([[u / r, v / r], [-v / q, u / q]])
        floor = np.diag(
            [
                self.range_std_floor**2 + (self.range_std_fraction * r) ** 2,
                self.bearing_std_floor**2,
            ]
        )
        R = J @ observation.cov[:2, :2] @ J.T + floor
        # odometry calibration, mount, camera calibration
        by_considered = np.hstack([np.zeros((2, 3)), -J, J @ observation.by_camera()[:2]])
        return observation.range_bearing, (R + R.T) / 2, by_considered

    def predict_measurement(self, landmark: MapLandmark) -> tuple[np.ndarray, np.ndarray]:
        """``h(mean)`` = [range, bearing] of the map landmark's centre, and its Jacobian ``H``."""
        dx, dy = np.asarray(landmark.centre[:2], dtype=float) - self.mean[:2]
        q = dx * dx + dy * dy
        r = math.sqrt(q)
        h = np.array([r, math.atan2(dy, dx) - self.mean[2]])
        H = np.array([[-dx / r, -dy / r, 0.0], [dy / q, -dx / q, -1.0]])
        return h, H

    def correct(self, observation: LandmarkObservation) -> bool:
        """One gated EKF update (Joseph form); ``True`` when the measurement was used."""
        z, R, by_considered = self.measurement(observation)
        if not self.min_range <= z[0] <= self.max_range:
            self.counters["out_of_range"] += 1
            return False
        h, H = self.predict_measurement(observation.landmark)
        nu = z - h
        nu[1] = wrap_angle(nu[1])
        correction = self.errors.correct(H, R, nu, self.gate, by_considered)
        if correction is None:
            self.counters["gated_out"] += 1
            candidate = robot_pose_from_landmark(
                observation.landmark, observation.z, observation.cov
            )
            found = self.relocaliser.rejected(*candidate, self.mean)
            if found is not None:  # lost (kidnapped): restart from the landmarks
                self.restart(*found)
                self.counters["relocalised"] += 1
            return False
        self.relocaliser.clear()
        self.mean = self.mean + correction
        self.mean[2] = wrap_angle(self.mean[2])
        self.cov = self.errors.P
        self.counters["landmark_updates"] += 1
        return True
