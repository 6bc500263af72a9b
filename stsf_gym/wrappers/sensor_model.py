"""The one seam between the simulator and the estimators: :func:`sensor_model` turns an env
into the :class:`SensorModel` an estimator runs on, and :func:`robot_map` gives the map the
robot knows (its landmarks and walls), which the camera's pointing uses too."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from stsf_gym.estimators import MapLandmark, SensorModel, estimator_settings
from stsf_gym.estimators.base import SonarRingModel
from stsf_gym.estimators.odometry_model import OdometryNoise
from stsf_gym.estimators.settings import OdometrySettings


def robot_map(env: gym.Env) -> tuple[dict[int, MapLandmark], np.ndarray]:
    """The map of ``env``'s current world as the robot knows it: its landmarks by id, and its
    wall segments, one ``[x1, y1, x2, y2]`` a row."""
    u = env.unwrapped
    landmarks = {
        lm.id: MapLandmark(lm.id, lm.centre, lm.normal, lm.square_centres) for lm in u.landmarks
    }
    return landmarks, np.array(u.config.world.walls, dtype=float).reshape(-1, 4)


def sensor_model(env: gym.Env, belief: OdometrySettings | None = None) -> SensorModel:
    """The model of ``env``'s robot for the current episode (call after each reset): its
    believed odometry calibration, believed camera calibration, mount and landmark map (never
    the true camera: ``camera_matrix`` and ``dist_coeffs`` are for evaluation), and the noise
    the estimator ``belief`` assumes (default: the nominal ``configs/estimators/odometry.yaml``),
    never the env's true noise settings."""
    u = env.unwrapped
    cfg = u.config
    belief = belief or estimator_settings("odometry")
    calibration = u.odometry_calibration
    landmarks, walls = robot_map(env)
    return SensorModel(
        calibration=calibration,
        odometry_noise=OdometryNoise.from_encoders(
            belief.slip_std,
            belief.radius_error_std,
            belief.wheelbase_error_std,
            (calibration.wheel_radius_left + calibration.wheel_radius_right) / 2,
        ),
        camera_calibration=u.camera_calibration,
        camera_calibration_std=(
            belief.principal_point_std_px / u.camera_calibration.K[0, 0],
            belief.focal_std,
        ),
        camera_matrix=u.camera_calibration.K,
        image_size=(cfg.camera.width, cfg.camera.height),
        robot_from_camera=u.camera_mount,
        landmarks=landmarks,
        pattern=cfg.world.landmark_pattern,
        walls=walls,
        wall_thickness=cfg.world.wall_thickness,
        sonar=SonarRingModel(
            axes=np.asarray(u.sonar.axes, dtype=float),
            ring_radius=u.sonar.origin_radius,
            min_range=cfg.sonar.min_range,
            max_range=cfg.sonar.max_range,
            noise_std=cfg.sonar.noise_std,
            noise_std_per_m=cfg.sonar.noise_std_per_m,
        ),
        body_radius=cfg.robot.body_radius,
    )
