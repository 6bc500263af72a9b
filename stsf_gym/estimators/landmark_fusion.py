"""The landmark estimators of the paper: conventional fusion and STSF, on one machinery.

Every step starts with the odometry prediction. On each camera frame, every detected map
landmark seen in the previous frame too gives a measurement of its pose relative to the robot,
``z = [x, y, phi]``:

- its range by motion stereo between the two frames (eq. 8-20), the camera motion taken from
  odometry and the plane normal from the board's measured orientation;
- its bearing and orientation from the board's image (planar PnP,
  :mod:`stsf_gym.estimators.landmark_observation`).

**Conventional** fusion uses that measurement of the current two frames: the paper's
(``conventional``, :mod:`stsf_gym.estimators.conventional`) takes the robot pose it gives as
the estimate, keeping nothing else; ``conventional-filter`` merges it with the odometry
prediction, so the estimate keeps what earlier pairs measured. **STSF** keeps the
landmark's track: each earlier measurement is carried into the current frame by the odometry
between frames (eq. 3, with its uncertainty and the correlation between reused frames) and
all are fused with the significance weights of eq. 4-5 (eq. 2); conventional fusion is the
track of one frame. Through the landmark's map pose the result becomes a measurement of the
robot's pose, merged with the odometry prediction by eq. 23-24 after a Mahalanobis gate
(chi-square, 3 dof), so a wrong detection is rejected rather than fused; when
``relocalise_after`` rejected measurements agree with each other instead, the robot was moved
(kidnapped) and the estimate starts again from them (:mod:`stsf_gym.estimators.relocalise`).
STSF's fused track reuses frames already merged into the estimate, shares the odometry since
each frame with it, and every motion-stereo baseline depends on the same unknown wheel
calibration as the prediction; the merge keeps those correlations
(:class:`~stsf_gym.estimators.pose_errors.PoseErrors`), so each frame's information counts
once. A track is dropped after ``max_gap_frames`` frames without the landmark. With
``matching: track-aided`` (STSF's default) every track predicts where its board appears in the
next frame and at what size (:mod:`stsf_gym.estimators.board_prediction`), and a board the
detector misses is searched there (:mod:`stsf_gym.vision.predicted`).

The two frames of a pair are the current frame and the landmark's last key frame at least
``min_baseline`` metres of odometry earlier: at 5 Hz and 12 cm/s consecutive frames are
2.4 cm apart, too little parallax for motion stereo. A range whose predicted standard
deviation exceeds ``max_relative_range_std`` of itself is dropped: its first-order variance
no longer describes its error.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

import numpy as np

from stsf_gym.estimators.base import SensorModel, chi_square_gate
from stsf_gym.estimators.board_prediction import board_outline, predict_board
from stsf_gym.estimators.frame_detector import FrameDetector
from stsf_gym.estimators.landmark_observation import (
    LandmarkObservation,
    observe,
    robot_pose_from_landmark,
    robot_pose_jacobian,
)
from stsf_gym.estimators.odometry_estimator import OdometryEstimator
from stsf_gym.estimators.odometry_model import odometry_step
from stsf_gym.estimators.pair_range import matched_rays, pair_range, pair_ranges
from stsf_gym.estimators.relocalise import Relocaliser
from stsf_gym.estimators.settings import ConventionalSettings, STSFSettings
from stsf_gym.fusion import STSFTrack
from stsf_gym.geometry import compose_with_jacobians, to_se3, wrap_angle
from stsf_gym.vision.predicted import BoardPrediction, PredictedMatcher


class _Seen:
    """The last frame a landmark was seen in, and the odometry since then: the motion (the
    baseline of the next pair), its slip covariance and its Jacobian by the calibration errors
    ``c`` (:mod:`~stsf_gym.estimators.pose_errors`), which every baseline of the episode shares
    with the prediction."""

    def __init__(self, observation: LandmarkObservation) -> None:
        self.observation = observation
        self.motion, self.slip_cov, self.by_calibration = (
            np.zeros(3),
            np.zeros((3, 3)),
            np.zeros((3, 3)),
        )
        self.missed = 0

    def move(self, u: np.ndarray, q_slip: np.ndarray, g_c: np.ndarray) -> None:
        """Compose one step's odometry increment ``u`` (slip covariance ``q_slip``, Jacobian
        ``g_c`` by ``c``) onto the motion."""
        self.motion, j_a, j_b = compose_with_jacobians(self.motion, u)
        self.slip_cov = j_a @ self.slip_cov @ j_a.T + j_b @ q_slip @ j_b.T
        self.by_calibration = j_a @ self.by_calibration + j_b @ g_c


class LandmarkFusionEstimator(OdometryEstimator):
    """Shared machinery of the conventional estimators and :class:`STSFEstimator`: landmark
    tracks of at most ``max_track_frames`` frames, fused with ``weights`` (eq. 2-5); the rest of
    the settings in ``configs/estimators/conventional.yaml``."""

    sensors = ("encoders", "camera")

    def __init__(self, settings: ConventionalSettings, max_track_frames: int, weights: str) -> None:
        super().__init__(settings)
        self.max_track_frames, self.weights = max_track_frames, weights
        s = settings
        self.sigma_px, self.max_gap_frames = s.sigma_px, s.max_gap_frames
        self.max_range = s.max_range
        self.min_baseline, self.max_relative_range_std = s.min_baseline, s.max_relative_range_std
        self.orientation_var_floor = s.orientation_std_floor**2
        self.position_std_floor = s.position_std_floor
        self.position_std_per_m = s.position_std_per_m
        self.gate = chi_square_gate(s.gate_probability, dof=3)
        self.relocaliser = Relocaliser(s.relocalise_after, s.relocalise_inflation, self.gate)
        self.matching, self.aided_search_px = s.matching, s.aided_search_px
        self.aided_limits = (s.aided_min_correlation, s.aided_min_board_px)

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        super().reset(model, initial_pose, initial_cov)
        matcher = None
        if self.matching == "track-aided":
            matcher = PredictedMatcher(model.pattern, *self.aided_limits)
        self.detector = FrameDetector(
            model.pattern, set(model.landmarks), model.camera_calibration, matcher
        )
        self.seen: dict[int, _Seen] = {}
        self.tracks: dict[int, STSFTrack] = {}
        #: each predicted landmark's board outline (:func:`board_outline`), once per episode
        self.outlines: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.frame_count = 0
        self.relocaliser.clear()

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        with self.timed("odometry"):
            travel = self.predict(obs)
            noise = self.model.odometry_noise
            u, _, G, G_c = odometry_step(np.zeros(3), *travel, self.model.calibration.wheelbase)
            q_slip = G @ noise.slip_cov(*travel) @ G.T
            for seen in self.seen.values():
                seen.move(u, q_slip, G_c)
            q_track = q_slip + G_c @ noise.calibration_cov @ G_c.T  # for the weights (eq. 4-5)
            for track in self.tracks.values():
                track.move(u, q_track)
        if obs["image_new"]:
            self._frame(obs)
        return self.mean, self.cov

    def _frame(self, obs: dict) -> None:
        self.counters["frames"] += 1
        pan, tilt = (float(a) for a in obs["camera_pan_tilt"])
        with self.timed("detect"):
            detections = self.detector(obs, self._predictions(pan, tilt))
        aided = {d.landmark_id for d in self.detector.aided}
        observed = set()
        for detection in detections:
            with self.timed("observe"):
                current = observe(detection, self.model, pan, tilt, self.sigma_px)
            if current is None or current.range_bearing[0] > self.max_range:
                continue
            observed.add(current.landmark.id)
            previous = self.seen.get(current.landmark.id)
            if previous is not None:
                previous.missed = 0
                if np.hypot(*previous.motion[:2]) < self.min_baseline:
                    continue  # too short a baseline yet: keep the earlier frame
            self.seen[current.landmark.id] = _Seen(current)
            if previous is None:
                continue
            with self.timed("motion_stereo"):
                measured = self._pair_measurement(previous, current)
            if measured is None:
                continue
            with self.timed("fusion"):
                self._fuse(current, *measured)
        self.counters["frames_matched"] += bool(observed)
        self.counters["frames_matched_aided_only"] += bool(observed) and observed <= aided
        for landmark_id in set(self.seen) - observed:
            self.seen[landmark_id].missed += 1
            if self.seen[landmark_id].missed > self.max_gap_frames:
                del self.seen[landmark_id]
                self._drop_track(landmark_id)

    def _predictions(self, pan: float, tilt: float) -> Callable[[], list[BoardPrediction]]:
        """Where each tracked landmark's board must appear in this frame (track-aided matching
        only; none otherwise): a function that makes them from the tracks as they are now, for
        the detector to call when it needs them."""
        if self.detector.matcher is None:
            return list
        # the frame and motion each track has now (a later step replaces, never mutates them)
        tracked = [(i, seen.observation.z, seen.motion) for i, seen in self.seen.items()]

        def predict() -> list[BoardPrediction]:
            camera_from_robot = np.linalg.inv(self.model.robot_from_camera(pan, tilt))
            predictions = []
            for landmark_id, z, motion in tracked:
                if landmark_id not in self.outlines:
                    self.outlines[landmark_id] = board_outline(
                        self.model.landmarks[landmark_id], self.model
                    )
                predicted = predict_board(
                    landmark_id,
                    self.outlines[landmark_id],
                    z,
                    motion,
                    camera_from_robot,
                    self.model.camera_calibration,
                    self.aided_search_px,
                )
                if predicted is not None:
                    predictions.append(predicted)
            return predictions

        return predict

    def _pair_measurement(
        self, previous: _Seen, current: LandmarkObservation
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """``z`` with its range from motion stereo between the two frames, its covariance
        (pixels, slip, floors) and its Jacobian by the calibration errors ``c``."""
        prev_obs = previous.observation
        camera_from_robot = current.robot_from_camera[:3, :3].T
        phi = current.z[2]
        normal = camera_from_robot @ -np.array([np.cos(phi), np.sin(phi), 0.0])
        rays = matched_rays(
            dict(zip(prev_obs.indices.tolist(), prev_obs.image_points, strict=True)),
            dict(zip(current.indices.tolist(), current.image_points, strict=True)),
            self.model.camera_matrix,
        )
        if rays is None:
            return None
        prev_camera_from_robot = np.linalg.inv(prev_obs.robot_from_camera)

        def prev_from_curr(motion: np.ndarray) -> np.ndarray:
            return prev_camera_from_robot @ to_se3(motion) @ current.robot_from_camera

        measured = pair_range(
            rays,
            prev_from_curr(previous.motion),
            normal,
            previous.slip_cov,
            camera_from_robot,
            self.sigma_px,
        )
        if measured is None:
            return None
        D, var_D = measured
        # dD / d(motion), by forward differences
        shifted = [previous.motion + step for step in np.eye(3) * 1e-6]
        shifted_D = pair_ranges(rays, [prev_from_curr(motion) for motion in shifted], normal)
        if None in shifted_D:
            return None
        by_motion = (np.array(shifted_D) - D) / 1e-6
        by_calibration = by_motion @ previous.by_calibration  # dD / dc
        calibration_var = (
            by_calibration @ self.model.odometry_noise.calibration_cov @ by_calibration
        )
        if var_D + calibration_var > (self.max_relative_range_std * D) ** 2:
            self.counters["imprecise"] += 1  # beyond where the first-order variance holds
            return None
        # the board centre along its PnP ray, at the plane distance D from the camera
        centre_cam = np.linalg.inv(current.robot_from_camera) @ np.append(
            [*current.z[:2], self.model.landmarks[current.landmark.id].centre[2]], 1.0
        )
        ray = centre_cam[:3] / np.linalg.norm(centre_cam[:3])
        if normal @ ray <= 1e-3:
            return None
        scale = 1.0 / float(normal @ ray)
        centre_robot = current.robot_from_camera[:3, :3] @ (D * scale * ray)
        centre_robot += current.robot_from_camera[:3, 3]
        z = np.array([centre_robot[0], centre_robot[1], phi])
        radial = (current.robot_from_camera[:3, :3] @ ray)[:2]  # the camera ray, on the floor
        radial /= np.linalg.norm(radial)
        project_out = np.eye(3)
        project_out[:2, :2] -= np.outer(radial, radial)
        cov = project_out @ current.cov @ project_out.T  # keep bearing and orientation
        cov[:2, :2] += var_D * scale**2 * np.outer(radial, radial)  # range from motion stereo
        # errors the model leaves out (the body's pitch and roll on its casters, the mount's
        # play): independent floors, which also keep the PnP covariance from being singular
        position_std = self.position_std_floor + self.position_std_per_m * np.hypot(*z[:2])
        cov += np.diag([position_std**2, position_std**2, self.orientation_var_floor])
        by_range = np.append(current.robot_from_camera[:2, :3] @ (scale * ray), 0.0)  # dz / dD
        return z, cov, np.outer(by_range, by_calibration)

    def _fuse(
        self, current: LandmarkObservation, z: np.ndarray, cov: np.ndarray, by_calibration
    ) -> None:
        """Add the frame's measurement ``z`` (covariance ``cov``, Jacobian ``by_calibration``
        by ``c``) to the landmark's track, fuse the track (eq. 2-5) and merge the robot pose it
        gives with the estimate (eq. 23-24, gated, with its correlations kept). A rejected
        frame goes to the re-localisation rule (:mod:`stsf_gym.estimators.relocalise`) with the
        robot pose of its board alone (PnP): a motion-stereo range needs the odometry, which is
        what may have gone wrong."""
        landmark = current.landmark
        track = self.tracks.setdefault(landmark.id, STSFTrack(self.max_track_frames))
        calibration_cov = self.model.odometry_noise.calibration_cov
        track.add(z, cov + by_calibration @ calibration_cov @ by_calibration.T)
        self.frame_count += 1
        pose_cov, by_considered = self._robot_pose_errors(current, z, cov, by_calibration)
        self.errors.add((landmark.id, self.frame_count), pose_cov, by_considered)
        keys = [key for key in self.errors.keys if key[0] == landmark.id]
        self.errors.remove(keys[: len(keys) - len(track)])  # the frames the track let go
        fused = track.fuse(self.weights)
        # the weights on the landmark's pose, as weights on the robot poses it gives
        jac = robot_pose_jacobian(landmark, fused.x)
        weights = {
            key: jac @ w @ np.linalg.inv(jac)
            for key, w in zip(keys[-len(track) :], fused.weights, strict=True)
        }
        fused_pose, _ = robot_pose_from_landmark(landmark, fused.x, fused.cov)
        innovation = fused_pose - self.mean
        innovation[2] = wrap_angle(innovation[2])
        correction = self.errors.merge(weights, innovation, self.gate)
        if correction is None:
            self._drop_track(landmark.id)
            self._rejected(current)
            return
        self._accepted(self.mean + correction)

    def _robot_pose_errors(
        self, current: LandmarkObservation, z: np.ndarray, cov: np.ndarray, by_calibration
    ) -> tuple[np.ndarray, np.ndarray]:
        """The covariance of the independent error of the robot pose that ``z`` gives, and
        its Jacobian by the considered errors (calibration, mount, camera)."""
        jac = robot_pose_jacobian(current.landmark, z)
        # a camera mounted m off puts the landmark -m off in the robot frame
        by_camera = jac @ current.by_camera()
        return jac @ cov @ jac.T, np.hstack([jac @ by_calibration, -jac[:, :2], by_camera])

    def _accepted(self, mean: np.ndarray) -> None:
        """A landmark measurement passed the gate: the estimate is now ``mean`` and
        ``errors.P``."""
        self.relocaliser.clear()
        self.mean = mean
        self.mean[2] = wrap_angle(self.mean[2])
        self.cov = self.errors.P
        self.counters["landmark_updates"] += 1

    def _rejected(self, current: LandmarkObservation) -> None:
        """A measurement of ``current``'s board was gated out: it goes to the re-localisation
        rule with the robot pose of its board alone."""
        self.counters["gated_out"] += 1
        candidate = robot_pose_from_landmark(current.landmark, current.z, current.cov)
        found = self.relocaliser.rejected(*candidate, self.mean)
        if found is not None:  # lost (kidnapped): start again from the landmarks
            self.restart(*found)
            self.tracks.clear()
            self.counters["relocalised"] += 1

    def _drop_track(self, landmark_id: int) -> None:
        self.tracks.pop(landmark_id, None)
        self.errors.remove([key for key in self.errors.keys if key[0] == landmark_id])


class ConventionalFilterEstimator(LandmarkFusionEstimator):
    """Conventional fusion as a filter: the landmark measured from the current two frames,
    merged with the odometry prediction (so the estimate keeps earlier pairs' information)."""

    name = "conventional-filter"
    settings_type: ClassVar[type] = ConventionalSettings

    def __init__(self, settings: ConventionalSettings) -> None:
        super().__init__(settings, max_track_frames=1, weights="significance")


class STSFEstimator(LandmarkFusionEstimator):
    """STSF: every frame of the landmark's track carried into the current one and fused."""

    name = "stsf"
    settings_type: ClassVar[type] = STSFSettings

    def __init__(self, settings: STSFSettings) -> None:
        super().__init__(settings, settings.max_track_frames, settings.weights)
