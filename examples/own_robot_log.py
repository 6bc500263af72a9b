"""A log of your own robot in stsf-gym's format, written by a plain script, then replayed.

No simulator: a robot drives 6 m along a corridor at 0.3 m/s; its camera, panned 60 degrees to
the left, sees boards on the left wall. The script writes what a real robot would log
(docs/log_format.md): the sensor model (odometry calibration, camera, mount, landmark map) as
JSON, the start pose, cumulative wheel ticks every control step, the mount angles and the
detected boards of every camera frame, and the true pose (here known; on a real robot from
motion capture) for scoring. Then ``stsf-gym replay`` runs the estimators on it::

    python examples/own_robot_log.py --out out/own_robot
    stsf-gym replay out/own_robot/own_robot.mcap --estimators odometry,stsf,ekf --out out/r

(the script runs the second step itself and prints the table).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from stsf_gym.camera_model import CameraCalibration, PanTiltMount
from stsf_gym.estimators import MapLandmark, SensorModel
from stsf_gym.estimators.odometry_model import OdometryNoise
from stsf_gym.geometry import OdometryCalibration
from stsf_gym.recording import ros_messages as ros
from stsf_gym.recording import topics
from stsf_gym.recording.mcap_writer import McapLogWriter
from stsf_gym.recording.sensor_model_json import sensor_model_json
from stsf_gym.vision.landmarks import LandmarkPattern, square_centres

DT, SPEED, SECONDS, FRAME_EVERY = 0.1, 0.3, 20.0, 2  # s, m/s, s, control steps per frame
TICKS, RADIUS, WHEELBASE = 2048, 0.05, 0.30  # believed odometry calibration
TRUE_RADII = (0.0502, 0.0499)  # the real wheels differ a little from the believed ones
PAN, CAMERA_AT = math.radians(60), (0.10, 0.0, 0.40)  # mount angle; mount in the robot frame
PIXEL_STD = 0.3
BOARDS_AT = [1.0, 2.2, 3.4, 4.6, 5.8]  # x of the boards on the left wall (y = 1)


def sensor_model() -> SensorModel:
    """What the robot knows: a hand-written model, as for a real robot."""
    K = np.array([[300.0, 0.0, 159.5], [0.0, 300.0, 119.5], [0.0, 0.0, 1.0]])
    pattern = LandmarkPattern()
    normal, up = np.array([0.0, -1.0, 0.0]), np.eye(3)[2]  # boards face the corridor
    right = np.cross(up, normal)  # as a viewer facing the board sees it
    landmarks = {}
    for landmark_id, x in enumerate(BOARDS_AT, start=1):
        centre = np.array([x, 1.0, 0.40])
        plane = square_centres(landmark_id, pattern)
        world = centre + plane[:, :1] * right + plane[:, 1:2] * up
        landmarks[landmark_id] = MapLandmark(landmark_id, centre, normal, world)
    return SensorModel(
        calibration=OdometryCalibration(TICKS, RADIUS, RADIUS, WHEELBASE),
        odometry_noise=OdometryNoise(slip_var_per_m=1e-5, radius_var=1e-5, wheelbase_var=1e-5),
        camera_calibration=CameraCalibration(K, np.zeros(5)),
        camera_calibration_std=(0.002, 0.01),
        camera_matrix=K,
        image_size=(320, 240),
        robot_from_camera=PanTiltMount(*CAMERA_AT),
        landmarks=landmarks,
        pattern=pattern,
        walls=np.array([[-1.0, 1.0, 8.0, 1.0], [-1.0, -1.0, 8.0, -1.0]]),
    )


def detections(model: SensorModel, pose: np.ndarray, rng) -> tuple[np.ndarray, np.ndarray]:
    """Each fully visible board's square centres in pixels: ``(slot ids, (slots, M, 2))``."""
    x, y, yaw = pose
    world_from_robot = np.eye(4)
    world_from_robot[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
    world_from_robot[:2, 3] = x, y
    camera_from_world = np.linalg.inv(world_from_robot @ model.robot_from_camera(PAN, 0.0))
    width, height = model.image_size
    ids, slots = [], []
    for landmark in model.landmarks.values():
        points = landmark.square_centres @ camera_from_world[:3, :3].T + camera_from_world[:3, 3]
        uv = model.camera_calibration.project(points)
        inside = np.isfinite(uv).all() and (uv >= 0).all() and (uv < [width, height]).all()
        if inside:
            ids.append(landmark.id)
            slots.append(uv + rng.normal(0.0, PIXEL_STD, uv.shape))
    per_slot = model.pattern.grid**2  # room for every square of a board
    padded = np.full((len(slots), per_slot, 2), np.nan)
    for slot, uv in zip(padded, slots, strict=True):
        slot[: len(uv)] = uv
    return np.array(ids, np.int64), padded


def write_log(path: Path, seed: int = 0) -> Path:
    """Drive the synthetic robot and write its log."""
    rng = np.random.default_rng(seed)
    model = sensor_model()
    log = McapLogWriter(path)
    log.write(topics.SENSOR_MODEL, 0, ros.string(sensor_model_json(model)))
    log.write(topics.EPISODE, 0, ros.string(json.dumps({"control_dt": DT, "world": "own"})))
    start, start_cov = np.zeros(3), np.diag([0.01, 0.01, 0.005]) ** 2
    log.write(topics.INITIAL_POSE, 0, ros.pose_with_covariance(0, "map", start, start_cov))
    wheel_angle = np.zeros(2)
    for k in range(round(SECONDS / DT) + 1):
        stamp = round(k * DT * 1e9)
        pose = np.array([SPEED * k * DT, 0.0, 0.0])
        if k:  # both wheels roll the step's distance, each with its own true radius
            wheel_angle += SPEED * DT / np.array(TRUE_RADII) * (1 + rng.normal(0, 1e-3, 2))
        ticks = np.floor(wheel_angle / (2 * math.pi) * TICKS)
        log.write(topics.WHEEL_TICKS, stamp, ros.joint_state(stamp, topics.WHEELS, ticks))
        log.write(
            topics.TRUTH, stamp, ros.pose_with_covariance(stamp, "map", pose, np.zeros((3, 3)))
        )
        if k % FRAME_EVERY == 0:
            log.write(
                topics.PAN_TILT, stamp, ros.joint_state(stamp, topics.MOUNT_JOINTS, [PAN, 0.0])
            )
            ids, slots = detections(model, pose, rng)
            points = ros.detection_slots(ids, slots.ravel())
            log.write(topics.DETECTIONS, stamp, ros.detection_cloud(stamp, points))
    log.close()
    return path


def main() -> None:
    from stsf_gym.experiments.replay import replay_logs

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=Path("out/own_robot"))
    args = parser.parse_args()
    path = write_log(args.out / "own_robot.mcap")
    summary = replay_logs([path], ["odometry", "stsf", "ekf"], args.out / "replay")
    for row in summary["rows"]:
        print(
            f"{row['estimator']:>10}: ATE {row['ate_rmse_m']['mean']:.3f} m, "
            f"final error {row['final_error_m']['mean']:.3f} m, "
            f"frames matched {row['match_rate']['mean'] or 0:.2f}"
        )
    print(f"Wrote {path} and {args.out / 'replay'}/results.json")


if __name__ == "__main__":
    main()
