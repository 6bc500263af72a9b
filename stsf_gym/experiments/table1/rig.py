"""The rig of Table I: the robot stops at places in front of one landmark and captures frames.

The experimenter drives the robot (on its true pose, as one places a robot by hand) along a
straight line past the board, oblique to its normal: forwards from the start place towards
the board's wall, then backwards away from it, stopping where the camera is the place's
distance from the board's plane. The camera thus moves sideways to its line of sight as well
as along it: motion stereo needs that parallax. At each place
it waits for the body to settle and captures ``frames_per_place`` frames with the camera
panned onto the board from the odometry pose (:class:`LandmarkPointer`). What the robot knows
is kept in a :class:`~stsf_gym.experiments.table1.measure.Place`: the detector's square centres
(:class:`FrameDetector`: undistorted with the believed calibration) averaged over the frames,
its believed camera pose, and the odometry motion since the previous place with its covariance
(the estimators' dead reckoning, :class:`OdometryEstimator`). Beside it, for evaluation: the
true plane distance of the camera and the true distance it moved from the previous place.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import stsf_gym  # noqa: F401 - registers the env ids
from stsf_gym.estimators import make_estimator
from stsf_gym.estimators.camera_pointing import LandmarkPointer
from stsf_gym.estimators.frame_detector import FrameDetector
from stsf_gym.estimators.odometry_estimator import OdometryEstimator
from stsf_gym.experiments.table1.measure import Place, average_features
from stsf_gym.geometry import to_se3, wrap_angle
from stsf_gym.wrappers import sensor_model

SETTLE_S = 1.0  # wait at a place before capturing: the body stops rocking on its casters
STOP_TOLERANCE = 0.003  # m from the place's distance


@dataclass
class Truth:
    """The place as it really was (for evaluation): camera plane distance and travel."""

    distance: float  # true plane distance of the camera, mean over the place's frames
    driven: float  # true distance the camera moved since the previous place
    heading: float  # the robot's true heading (rad)


class Table1Rig:
    """One seeded episode: ``capture(distances)`` stops at each and returns what it saw."""

    def __init__(
        self,
        env_config: dict,
        seed: int,
        speed: float,
        frames_per_place: int,
        approach_deg: float,
    ) -> None:
        self.env = gym.make("stsf_gym/Corridor-v0", config=env_config)
        self.seed, self.speed, self.frames_per_place = seed, speed, frames_per_place
        self.approach = math.radians(approach_deg)
        u = self.env.unwrapped
        self.landmark = u.landmarks[0]
        self.camera_forward = u.config.robot.camera_forward
        self.scale = np.array(
            [
                u.config.robot.max_speed,
                u.config.robot.max_yaw_rate,
                math.radians(u.config.robot.pan_limit_deg),
            ]
        )

    def capture(self, distances: list[float]) -> tuple[list[Place], list[Truth]]:
        """Places at ``distances`` (m from the board's plane, the first the start), on a line
        at ``approach_deg`` to the board's normal that crosses the normal halfway through
        the range of distances, so the robot passes in front of the board."""
        normal, board = self.landmark.normal[:2], self.landmark.centre[:2]
        tangent = np.array([-normal[1], normal[0]])
        slope = math.tan(self.approach)
        travel = -normal * math.cos(self.approach) + tangent * math.sin(self.approach)
        heading = math.atan2(travel[1], travel[0])  # towards the board's wall
        middle = (max(distances) + min(distances)) / 2
        camera = board + normal * distances[0] + tangent * slope * (middle - distances[0])
        start = camera - self.camera_forward * travel
        try:
            _, self.info = self.env.reset(seed=self.seed, options={"start_pose": [*start, heading]})
            self.model = sensor_model(self.env)
            self.detector = FrameDetector(
                self.model.pattern, {self.landmark.id}, self.model.camera_calibration
            )
            self.pointer = LandmarkPointer(
                self.model.landmarks,
                self.model.walls,
                self.camera_forward,
                math.radians(self.env.unwrapped.config.robot.pan_limit_deg),
                max_range=math.inf,
            )
            self.odometry = self._dead_reckoning(self.info["true_pose"])
            self.since_place = self._dead_reckoning(np.zeros(3))
            places, truths, camera_at = [], [], None
            for distance in distances:
                self._drive_to(distance, heading)
                place, truth_distance, camera = self._capture_place()
                driven = 0.0 if camera_at is None else float(np.linalg.norm(camera - camera_at))
                places.append(place)
                truths.append(Truth(truth_distance, driven, float(self.info["true_pose"][2])))
                camera_at = camera
            return places, truths
        finally:
            self.env.close()

    def _motion_by_calibration(self) -> np.ndarray:
        """``J`` of the motion since the last place by the wheel calibration ``c``: the dead
        reckoning carries ``Cov(e, c) = J Sigma_c`` (:mod:`~stsf_gym.estimators.pose_errors`)."""
        errors = self.since_place.errors
        with_c = errors.joint[0:3, errors.considered][:, :3]
        return with_c @ np.linalg.pinv(self.model.odometry_noise.calibration_cov)

    def _dead_reckoning(self, pose: np.ndarray) -> OdometryEstimator:
        odometry = make_estimator("odometry")
        odometry.reset(self.model, pose, np.zeros((3, 3)))
        return odometry

    def _camera_distance(self) -> float:
        """The true camera's distance from the board's plane, from the robot's true pose."""
        x, y, yaw = self.info["true_pose"]
        camera = np.array([x, y]) + self.camera_forward * np.array([math.cos(yaw), math.sin(yaw)])
        return float(self.landmark.normal[:2] @ (camera - self.landmark.centre[:2]))

    def _step(self, v: float, w: float) -> dict:
        pan = self.pointer.pan(self.odometry.mean)
        action = np.clip(np.array([v, w, pan]) / self.scale, -1, 1).astype(np.float32)
        obs, _, terminated, truncated, self.info = self.env.step(action)
        if terminated or truncated:
            raise RuntimeError(f"table1 rig stopped early (collision: {self.info['collision']})")
        self.odometry.predict(obs)
        self.since_place.predict(obs)
        return obs

    def _drive_to(self, distance: float, heading: float) -> None:
        """Forwards (towards the board) or backwards until the camera is at ``distance``."""
        while abs(error := self._camera_distance() - distance) > STOP_TOLERANCE:
            v = math.copysign(min(self.speed, 0.5 * abs(error) + 0.01), error)
            self._step(v, -2.0 * float(wrap_angle(self.info["true_pose"][2] - heading)))
        for _ in range(round(SETTLE_S / self.env.unwrapped.dt)):
            self._step(0.0, 0.0)

    def _capture_place(self) -> tuple[Place, float, np.ndarray]:
        frames, truth, pan_tilt = [], [], None
        while len(frames) < self.frames_per_place:
            obs = self._step(0.0, 0.0)
            if not obs["image_new"]:
                continue
            found = [d for d in self.detector(obs) if d.landmark_id == self.landmark.id]
            points = {}
            if found:
                points = dict(zip(found[0].indices.tolist(), found[0].image_points, strict=True))
            frames.append(points)
            camera = self.info["camera_pose"][:3, 3]
            truth.append(float(self.landmark.normal @ (camera - self.landmark.centre)))
            pan_tilt = obs["camera_pan_tilt"]
        pose = self.odometry.mean
        place = Place(
            points=average_features(frames),
            frames=sum(bool(points) for points in frames),
            world_from_camera=to_se3(pose) @ self.model.robot_from_camera(*map(float, pan_tilt)),
            heading=float(pose[2]),
            motion=self.since_place.mean.copy(),
            motion_cov=self.since_place.cov.copy(),
            pose=pose.copy(),
            motion_by_calibration=self._motion_by_calibration(),
        )
        self.since_place.restart(np.zeros(3), np.zeros((3, 3)))
        return place, float(np.mean(truth)), self.info["camera_pose"][:3, 3].copy()
