"""The modern reference: a fixed-lag factor-graph smoother (GTSAM's iSAM2 with a lag).

**Graph.** A ``Pose2`` variable ``x_i`` per camera frame, and one 7-vector ``k`` of the
considered parameters (wheel radii and wheelbase, camera mount, camera heading and focal
scale; :mod:`.measurements`), the same in every factor and never marginalised: the smoother
*estimates* the calibration the filters only consider. Factors:

- priors: the start pose ``N(x_0, P_0)`` and ``k ~ N(0, Sigma_k)``;
- odometry between consecutive frames: the preintegrated leg ``Delta`` with the slip
  covariance ``Q`` and the calibration Jacobian ``J_c`` (:func:`.factors.odometry_factor`);
- landmarks: each map board's PnP pose ``z = h(x_i) + M k + v`` (:func:`.factors.landmark_factor`).

**Fixed lag.** :class:`gtsam.IncrementalFixedLagSmoother` keeps the frames of the last
``window_s`` seconds; older poses are marginalised into a prior on what remains (iSAM2 updates
incrementally, relinearising a variable whose change exceeds ``relinearize_threshold``).

**Output.** At a camera frame the estimate is the smoothed newest pose with its marginal
covariance (iSAM2's, rotated from the pose's own frame to world axes): ``pose_cov``. Between
frames the odometry prediction moves it (as :class:`~..odometry_estimator.OdometryEstimator`).

**Gating** as the EKF's: a board whose innovation ``nu = z - h(x) - M k`` has
``nu^T S^-1 nu`` above the chi-square quantile of ``gate_probability`` (3 dof) with
``S = H P H^T + M Sigma_k M^T + R`` (the predicted pose's and ``k``'s marginal covariances) never
enters the graph. Boards outside ``[min_range, max_range]`` are not used. **Re-localisation**
as the others' (:mod:`~..relocalise`): when ``relocalise_after`` rejected boards agree, the
graph restarts there, ``k`` keeping its estimate and marginal covariance as its prior.

``counters``: ``frames``, ``frames_matched``, ``detections``, ``landmark_updates``, ``gated_out``,
``out_of_range``, ``unusable``, ``relocalised``.
"""

from __future__ import annotations

from typing import ClassVar

import gtsam
import numpy as np

from stsf_gym.estimators.base import SensorModel, chi_square_gate
from stsf_gym.estimators.frame_detector import FrameDetector
from stsf_gym.estimators.landmark_observation import observe
from stsf_gym.estimators.odometry_estimator import OdometryEstimator
from stsf_gym.estimators.references import factors
from stsf_gym.estimators.references.measurements import (
    CONSIDERED,
    LandmarkPose,
    OdometryLeg,
    considered_cov,
    landmark_pose,
)
from stsf_gym.estimators.relocalise import Relocaliser
from stsf_gym.estimators.settings import LandmarkPoseSettings, SmootherSettings

K_VARIANCE_FLOOR = 1e-12  # smallest variance of k's prior after a restart


class LandmarkPoses:
    """The boards of a camera frame as the graph's measurements (shared with the floor)."""

    def __init__(self, model: SensorModel, settings: LandmarkPoseSettings) -> None:
        self.model, self.settings = model, settings
        self.detector = FrameDetector(model.pattern, set(model.landmarks), model.camera_calibration)

    def __call__(self, obs: dict, counters: dict) -> list[LandmarkPose]:
        s, found = self.settings, []
        pan, tilt = (float(a) for a in obs["camera_pan_tilt"])
        detections = self.detector(obs)
        counters["frames"] += 1
        counters["frames_matched"] += bool(detections)
        for detection in detections:
            counters["detections"] += 1
            observation = observe(detection, self.model, pan, tilt, s.sigma_px)
            if observation is None:
                counters["unusable"] += 1
                continue
            measurement = landmark_pose(
                observation, s.position_std_floor, s.position_std_per_m, s.orientation_std_floor
            )
            if not s.min_range <= measurement.range <= s.max_range:
                counters["out_of_range"] += 1
                continue
            found.append(measurement)
        return found


class FixedLagSmoother(OdometryEstimator):
    """iSAM2 over the last ``window_s`` seconds of frames, calibration estimated.

    Settings (:class:`SmootherSettings`, ``configs/estimators/smoother.yaml``): ``window_s``,
    ``relinearize_threshold``, and the landmark measurement's (``sigma_px``, the floors,
    ``min_range``, ``max_range``, ``gate_probability``), ``mount_std`` and the re-localisation's.
    """

    name = "smoother"
    sensors = ("encoders", "camera")  # map boards in the camera frames
    settings_type: ClassVar[type] = SmootherSettings

    def __init__(self, settings: SmootherSettings) -> None:
        super().__init__(settings)
        self.gate = chi_square_gate(settings.gate_probability, dof=3)
        self.relocaliser = Relocaliser(
            settings.relocalise_after, settings.relocalise_inflation, self.gate
        )
        self.nis: list[tuple[float, int]] = []

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        super().reset(model, initial_pose, initial_cov)
        self.boards = LandmarkPoses(model, self.settings)
        self.relocaliser.clear()
        self.nis = []
        self.time = 0.0
        self.start_graph(
            self.mean, self.cov, np.zeros(CONSIDERED), considered_cov(model, self.mount_std)
        )

    def start_graph(self, pose, cov, considered, considered_covariance) -> None:
        """A new graph: the first frame at ``pose`` and ``k`` with these priors."""
        params = gtsam.ISAM2Params()
        params.setRelinearizeThreshold(self.settings.relinearize_threshold)
        self.smoother = gtsam.IncrementalFixedLagSmoother(self.settings.window_s, params)
        self.index, self.leg = 0, OdometryLeg()
        self.k, self.k_cov = np.asarray(considered, float), considered_covariance
        graph = gtsam.NonlinearFactorGraph()
        graph.add(factors.pose_prior(0, pose, cov))
        graph.add(factors.considered_prior(self.k, considered_covariance))
        values = gtsam.Values()
        values.insert(factors.pose_key(0), factors.as_pose2(pose))
        values.insert(factors.CONSIDERED_KEY, self.k)
        self._update(graph, values)

    def restart(self, mean: np.ndarray, cov: np.ndarray) -> None:
        super().restart(mean, cov)
        # k's marginal as its new prior, kept positive definite (round-off can leave a
        # direction the boards pinned down with a tiny negative eigenvalue)
        values, vectors = np.linalg.eigh(0.5 * (self.k_cov + self.k_cov.T))
        k_cov = (vectors * np.maximum(values, K_VARIANCE_FLOOR)) @ vectors.T
        self.start_graph(self.mean, self.cov, self.k, k_cov)

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        with self.timed("odometry"):
            self.leg.add(self.model, *self.predict(obs))
            self.time += dt
        if int(obs["image_new"]):
            with self.timed("detect"):
                boards = self.boards(obs, self.counters)
            with self.timed("update"):
                self.frame(boards)
        return self.mean, self.cov

    def frame(self, boards: list[LandmarkPose]) -> None:
        """A new frame's pose, its odometry leg and the boards that pass the gate."""
        restarts = self.counters["relocalised"]
        accepted = [board for board in boards if self.accepted(board)]
        if self.counters["relocalised"] > restarts:
            return  # the graph restarted at the boards' pose
        previous, self.index = self.index, self.index + 1
        graph = gtsam.NonlinearFactorGraph()
        graph.add(factors.odometry_factor(previous, self.index, self.leg))
        for board in accepted:
            graph.add(factors.landmark_factor(self.index, board))
        values = gtsam.Values()
        values.insert(factors.pose_key(self.index), factors.as_pose2(self.mean))
        self.leg = OdometryLeg()
        self._update(graph, values)

    def accepted(self, board: LandmarkPose) -> bool:
        """The gate (and, for a rejected board, the re-localisation's candidate)."""
        H, M = board.by_pose(self.mean), board.by_considered
        local = factors.world_to_local_cov(self.mean, self.cov)
        S = H @ local @ H.T + M @ self.k_cov @ M.T + board.noise
        nu = board.residual(self.mean, self.k)
        d2 = float(nu @ np.linalg.solve(S, nu))
        self.nis.append((d2, 3))
        if d2 <= self.gate:
            self.relocaliser.clear()
            self.counters["landmark_updates"] += 1
            return True
        self.counters["gated_out"] += 1
        candidate = board.robot_pose()
        jac = np.linalg.inv(H)  # the pose's error from the board's alone
        found = self.relocaliser.rejected(
            candidate, factors.local_to_world_cov(candidate, jac @ board.noise @ jac.T), self.mean
        )
        if found is not None:
            self.counters["relocalised"] += 1
            self.restart(*found)
        return False

    def _update(self, graph: gtsam.NonlinearFactorGraph, values: gtsam.Values) -> None:
        stamps = gtsam.FixedLagSmootherKeyTimestampMap()
        for key in values.keys():
            stamps.insert((key, self.time))
        stamps.insert((factors.CONSIDERED_KEY, self.time))  # k stays in the window
        self.smoother.update(graph, values, stamps)
        key = factors.pose_key(self.index)
        estimate = self.smoother.calculateEstimate()
        self.mean = factors.as_array(estimate.atPose2(key))
        self.k = estimate.atVector(factors.CONSIDERED_KEY)
        local = self.smoother.marginalCovariance(key)
        self.k_cov = self.smoother.marginalCovariance(factors.CONSIDERED_KEY)
        self.errors.restart(factors.local_to_world_cov(self.mean, local))
        self.cov = self.errors.P

    def innovations(self) -> list[tuple[float, int]]:
        return list(self.nis)
