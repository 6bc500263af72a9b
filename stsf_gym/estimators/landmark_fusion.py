"""The paper's estimators: conventional fusion (two frames) and STSF (all frames of a track).

Every step starts with the odometry prediction. On each camera frame, every detected map
landmark seen in the previous frame too gives a measurement of its pose relative to the robot,
``z = [x, y, phi]``:

- its range by motion stereo between the two frames (eq. 8-20), the camera motion taken from
  odometry and the plane normal from the board's measured orientation;
- its bearing and orientation from the board's image (planar PnP,
  :mod:`stsf_gym.estimators.landmark_observation`).

**Conventional** fusion uses that measurement of the current two frames. **STSF** keeps the
landmark's track: each earlier measurement is carried into the current frame by the odometry
between frames (eq. 3, with its uncertainty and the correlation between reused frames) and
all are fused with the significance weights of eq. 4-5 (eq. 2); conventional fusion is the
track of one frame. Through the landmark's map pose the result becomes a measurement of the
robot's pose, merged with the odometry prediction by eq. 23-24 after a Mahalanobis gate
(chi-square, 3 dof), so a wrong detection is rejected rather than fused; when
``relocalise_after`` rejected measurements agree with each other instead, the robot was moved
(kidnapped) and the estimate starts again from them (:mod:`stsf_gym.estimators.relocalise`).
STSF's fused track reuses frames already merged into the estimate, and shares the odometry
since each frame with it; the merge keeps that correlation
(:class:`~stsf_gym.estimators.carried_poses.CarriedPoses`), so each frame's information counts
once. A track is dropped after ``max_gap_frames`` frames without the landmark.

The two frames of a pair are the current frame and the landmark's last key frame at least
``min_baseline`` metres of odometry earlier: at 5 Hz and 12 cm/s consecutive frames are
2.4 cm apart, too little parallax for motion stereo. A range whose predicted standard
deviation exceeds ``max_relative_range_std`` of itself is dropped: its first-order variance
no longer describes its error.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from stsf_gym.estimators.base import SensorModel, chi_square_gate
from stsf_gym.estimators.carried_poses import CarriedPoses
from stsf_gym.estimators.dead_reckoning import OdometryEstimator
from stsf_gym.estimators.frame_detector import FrameDetector
from stsf_gym.estimators.landmark_observation import (
    LandmarkObservation,
    observe,
    robot_pose_from_landmark,
    robot_pose_jacobian,
)
from stsf_gym.estimators.odometry import odometry_step
from stsf_gym.estimators.pair_range import pair_range
from stsf_gym.estimators.relocalise import Relocaliser
from stsf_gym.fusion import STSFTrack
from stsf_gym.geometry import compose, compose_jacobians, to_se3, wrap_angle


class _Seen:
    """The last frame a landmark was seen in, and the odometry since then.

    The covariance of that motion, the baseline of the next pair, keeps slip and calibration
    apart: slip is a random walk, but the wheel-radius error is one scale per wheel, so over a
    short baseline of ``d`` metres its drift has the variance of the random walk matched at
    ``d`` (:class:`~stsf_gym.estimators.odometry.OdometryNoise`), far below that matched at
    the estimator's ``calibration_length``.
    """

    def __init__(self, observation: LandmarkObservation) -> None:
        self.observation = observation
        self.motion, self.distance = np.zeros(3), 0.0
        self.slip_cov, self.scale_cov = np.zeros((3, 3)), np.zeros((3, 3))
        self.missed = 0

    def move(self, u: np.ndarray, q_slip: np.ndarray, q_scale: np.ndarray) -> None:
        """Compose one step's odometry increment ``u`` onto the motion: ``q_slip`` is its slip
        covariance, ``q_scale`` its calibration covariance matched at 1 m."""
        j_a, j_b = compose_jacobians(self.motion, u)
        self.motion = compose(self.motion, u)
        self.distance += float(np.hypot(*u[:2]))
        self.slip_cov = j_a @ self.slip_cov @ j_a.T + j_b @ q_slip @ j_b.T
        self.scale_cov = j_a @ self.scale_cov @ j_a.T + j_b @ q_scale @ j_b.T

    @property
    def motion_cov(self) -> np.ndarray:
        return self.slip_cov + self.distance * self.scale_cov


class LandmarkFusionEstimator(OdometryEstimator):
    """Shared machinery of :class:`ConventionalEstimator` and :class:`STSFEstimator`: landmark
    tracks of at most ``max_track_frames`` frames, fused with ``weights`` (eq. 2-5)."""

    def __init__(
        self,
        max_track_frames: int,
        weights: str = "significance",
        sigma_px: float = 0.15,
        gate_probability: float = 0.99,
        max_gap_frames: int = 5,
        max_range: float = 9.0,
        min_baseline: float = 0.1,
        max_relative_range_std: float = 0.25,
        orientation_std_floor: float = 0.006,
        position_std_floor: float = 0.01,
        position_std_per_m: float = 0.005,
        relocalise_after: int = 3,
        relocalise_inflation: float = 4.0,
        calibration_length: float = 3.0,
    ) -> None:
        super().__init__(calibration_length)
        if weights not in ("significance", "gls"):
            raise ValueError(f"stsf weights must be 'significance' or 'gls', got {weights!r}")
        self.max_track_frames, self.weights = max_track_frames, weights
        self.sigma_px, self.max_gap_frames, self.max_range = sigma_px, max_gap_frames, max_range
        self.min_baseline, self.max_relative_range_std = min_baseline, max_relative_range_std
        self.orientation_var_floor = orientation_std_floor**2
        self.position_std_floor, self.position_std_per_m = position_std_floor, position_std_per_m
        self.gate = chi_square_gate(gate_probability, dof=3)
        self.relocaliser = Relocaliser(relocalise_after, relocalise_inflation, self.gate)
        self.detector: FrameDetector | None = None

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        super().reset(model, initial_pose, initial_cov)
        self.detector = FrameDetector(model.pattern, set(model.landmarks))
        self.seen: dict[int, _Seen] = {}
        self.tracks: dict[int, STSFTrack] = {}
        self.carried = CarriedPoses()
        self.noise = self.model.odometry_noise
        self.baseline_noises = (  # slip alone; calibration alone, matched at 1 m (see _Seen)
            replace(self.noise, radius_var=0.0),
            replace(self.noise, slip_var_per_m=0.0, calibration_length=1.0),
        )
        self.frame_count = 0
        self.relocaliser.clear()

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        with self.timed("odometry"):
            self.carried.predict(*self.predict(obs))
            calibration = self.model.calibration
            travel = calibration.wheel_travel(obs["encoders"])
            u, _, q = odometry_step(np.zeros(3), *travel, calibration.wheelbase, self.noise)
            q_slip, q_scale = (
                odometry_step(np.zeros(3), *travel, calibration.wheelbase, noise)[2]
                for noise in self.baseline_noises
            )
            for seen in self.seen.values():
                seen.move(u, q_slip, q_scale)
            for track in self.tracks.values():
                track.move(u, q)
        if obs["image_new"]:
            self._frame(obs)
        return self.mean, self.cov

    def _frame(self, obs: dict) -> None:
        self.counters["frames"] += 1
        with self.timed("detect"):
            detections = self.detector(obs)
        pan, tilt = (float(a) for a in obs["camera_pan_tilt"])
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
        for landmark_id in set(self.seen) - observed:
            self.seen[landmark_id].missed += 1
            if self.seen[landmark_id].missed > self.max_gap_frames:
                del self.seen[landmark_id]
                self._drop_track(landmark_id)

    def _pair_measurement(
        self, previous: _Seen, current: LandmarkObservation
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """``z`` with its range from motion stereo between the two frames, and covariance."""
        prev_obs = previous.observation
        camera_from_robot = current.robot_from_camera[:3, :3].T
        phi = current.z[2]
        normal = camera_from_robot @ -np.array([np.cos(phi), np.sin(phi), 0.0])
        prev_from_curr = (
            np.linalg.inv(prev_obs.robot_from_camera)
            @ to_se3(previous.motion)
            @ current.robot_from_camera
        )
        measured = pair_range(
            dict(zip(prev_obs.indices.tolist(), prev_obs.image_points, strict=True)),
            dict(zip(current.indices.tolist(), current.image_points, strict=True)),
            self.model.camera_matrix,
            prev_from_curr,
            normal,
            previous.motion_cov,
            camera_from_robot,
            self.sigma_px,
        )
        if measured is None:
            return None
        D, var_D = measured
        if var_D > (self.max_relative_range_std * D) ** 2:
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
        return z, cov

    def _fuse(self, current: LandmarkObservation, z: np.ndarray, cov: np.ndarray) -> None:
        """Add the frame's measurement ``z`` to the landmark's track, fuse the track (eq. 2-5)
        and merge the robot pose it gives with the estimate (eq. 23-24, gated, with the carried
        correlation). A rejected frame goes to the re-localisation rule
        (:mod:`stsf_gym.estimators.relocalise`) with the robot pose of its board alone (PnP):
        a motion-stereo range needs the odometry, which is what may have gone wrong."""
        landmark = current.landmark
        track = self.tracks.setdefault(landmark.id, STSFTrack(self.max_track_frames))
        track.add(z, cov)
        _, pose_cov = robot_pose_from_landmark(landmark, z, cov)
        self.frame_count += 1
        self.carried.add((landmark.id, self.frame_count), pose_cov)
        keys = [key for key in self.carried.keys if key[0] == landmark.id]
        self.carried.remove(keys[: len(keys) - len(track)])  # the frames the track let go
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
        merged = self.carried.merge(self.cov, weights, innovation, self.gate)
        if merged is None:
            self.counters["gated_out"] += 1
            self._drop_track(landmark.id)
            candidate = robot_pose_from_landmark(landmark, current.z, current.cov)
            found = self.relocaliser.rejected(*candidate, self.mean)
            if found is not None:  # lost (kidnapped): start again from the landmarks
                self.mean, self.cov = found
                self.tracks.clear()
                self.carried.clear()
                self.counters["relocalised"] += 1
            return
        self.relocaliser.clear()
        correction, self.cov = merged
        self.mean = self.mean + correction
        self.mean[2] = wrap_angle(self.mean[2])
        self.counters["landmark_updates"] += 1

    def _drop_track(self, landmark_id: int) -> None:
        self.tracks.pop(landmark_id, None)
        self.carried.remove([key for key in self.carried.keys if key[0] == landmark_id])


class ConventionalEstimator(LandmarkFusionEstimator):
    """Conventional sensor fusion: the landmark measured from the current two frames."""

    name = "conventional"

    def __init__(self, **options) -> None:
        super().__init__(max_track_frames=1, **options)


class STSFEstimator(LandmarkFusionEstimator):
    """STSF: every frame of the landmark's track carried into the current one and fused."""

    name = "stsf"

    def __init__(self, max_track_frames: int = 10, **options) -> None:
        super().__init__(max_track_frames=max_track_frames, **options)
