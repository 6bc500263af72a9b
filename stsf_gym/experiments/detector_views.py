"""Views of a landmark from chosen distances and angles: the frames detector statistics come from.

A 16 x 16 m room with one landmark on each of two opposite walls is large enough for oblique
views up to 60 degrees; the robot is placed so its camera looks at the board from a given
distance and angle off the board's normal. Used by the detector benchmark, the fit of the fast
sensor mode and the tests comparing the two.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from stsf_gym.camera_model import CameraCalibration
from stsf_gym.vision.predicted import BoardPrediction, PredictedMatcher

LANDMARK_ID = 77
DISTANCES = (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0)
ANGLES = (0.0, 15.0, 30.0, 45.0, 60.0)
TRACK_ERROR_PX = 2.0  # a track's prediction error per axis (benchmarks/track_aided_matching.py)


def room_world() -> dict:
    """A 16 x 16 m room: landmark 77 on the east wall, 200 on the west wall."""
    return {
        "name": "detector_room",
        "wall_height": 2.0,
        "wall_thickness": 0.1,
        "walls": [[-1, -8, 15, -8], [-1, 8, 15, 8], [-1, -8, -1, 8], [15, -8, 15, 8]],
        "path": [[0, 0], [10, 0]],
        "start": [0, 0, 0],
        "goal_radius": 0.3,
        "landmark_height": 0.9,
        "landmark_pattern": {"square_size": 0.05, "pitch": 0.10, "grid": 5, "border": 0.05},
        "landmarks": [
            {"id": LANDMARK_ID, "at": [15, 0], "facing_deg": 180},
            {"id": 200, "at": [-1, 0], "facing_deg": 0},
        ],
        "obstacles": [],
    }


def view_pose(board_xy, normal_deg, distance, angle_deg, yaw_jitter, camera_forward=0.10):
    """Robot pose whose camera is ``distance`` from the board, ``angle_deg`` off its normal."""
    a = math.radians(normal_deg + angle_deg)
    cam = np.asarray(board_xy) + distance * np.array([math.cos(a), math.sin(a)])
    yaw = a + math.pi + yaw_jitter
    axle = cam - camera_forward * np.array([math.cos(yaw), math.sin(yaw)])
    return [float(axle[0]), float(axle[1]), yaw]


def landmark_views(
    env, rng: np.random.Generator, distances=DISTANCES, angles=ANGLES, repeats: int = 3
) -> Iterator[tuple[float, float, dict, dict]]:
    """``(distance, angle, obs, info)`` for each view with the board wholly in view.

    ``env`` must be built on :func:`room_world`; angles alternate in sign over the repeats and
    the heading is jittered by up to 0.06 rad, all drawn from ``rng``.
    """
    u = env.unwrapped
    landmark = next(lm for lm in u.landmarks if lm.id == LANDMARK_ID)
    normal_deg = math.degrees(math.atan2(landmark.normal[1], landmark.normal[0]))
    forward = u.config.robot.camera_forward
    for distance in distances:
        for angle in angles:
            for r in range(repeats):
                sign = 1 if r % 2 == 0 else -1
                jitter = rng.uniform(-0.06, 0.06)
                pose = view_pose(
                    landmark.centre[:2], normal_deg, distance, sign * angle, jitter, forward
                )
                obs, info = env.reset(seed=int(rng.integers(2**31)), options={"start_pose": pose})
                if LANDMARK_ID in u.landmarks_in_view(info["camera_pose"]):
                    yield distance, angle, obs, info


def detection_records(
    env,
    rng: np.random.Generator,
    distances=DISTANCES,
    angles=ANGLES,
    repeats: int = 3,
    aided_rng: np.random.Generator | None = None,
) -> list[dict]:
    """What the env's camera pipeline detects of the board in each of :func:`landmark_views`.

    Works in both camera modes (the rendered image through the detector, or the fast mode's
    simulated detections), so the two can be compared. Each record: ``distance``, ``angle``,
    ``size_px`` (the board's apparent size, see
    :func:`stsf_gym.envs.sensors.fast_camera.apparent_size_px`), ``detected``, ``wrong_ids``
    (detections of other ids), ``residuals`` ((N, 2) pixels, detected minus true square centres
    through the true K and distortion: the sensor's error; empty when not detected) and
    ``calibrated_residuals`` (the same points as the estimators see them: undistorted with the
    episode's believed calibration, minus the true square centres projected through the believed K:
    the sensor's and the calibration's error). With ``aided_rng``, a view the detector missed
    is searched as STSF's track-aided matching does (its ``configs/estimators/stsf.yaml``
    settings), given the board's true corners off by a track's error (``TRACK_ERROR_PX`` per
    axis, drawn from ``aided_rng``): ``aided`` (None where the detector found it).
    """
    from stsf_gym.envs.sensors.fast_camera import apparent_size_px
    from stsf_gym.estimators.frame_detector import FrameDetector

    u = env.unwrapped
    landmark = next(lm for lm in u.landmarks if lm.id == LANDMARK_ID)
    pattern, ids = u.config.world.landmark_pattern, {lm.id for lm in u.landmarks}
    detector = FrameDetector(pattern, ids)
    aided_detector, search_px = _aided_detector(pattern, ids)
    records = []
    for distance, angle, obs, info in landmark_views(env, rng, distances, angles, repeats):
        pose = info["camera_pose"]
        detections = detector(obs)
        good = [d for d in detections if d.landmark_id == LANDMARK_ID]
        residuals = calibrated = np.zeros((0, 2))
        if good:
            points, rows = good[0].image_points, good[0].indices
            residuals = points - u.camera.project(pose, landmark.square_centres)[rows]
            believed = u.camera_calibration
            pinhole = CameraCalibration(believed.K, np.zeros(5))
            camera_points = world_to_camera(pose, landmark.square_centres)
            calibrated = believed.undistort_pixels(points) - pinhole.project(camera_points)[rows]
        aided = None
        if aided_rng is not None and not good:
            corners = u.camera.project(pose, landmark.board_corners)
            shifted = corners + aided_rng.normal(0.0, TRACK_ERROR_PX, 2)
            prediction = BoardPrediction(LANDMARK_ID, shifted, search_px)
            aided_detector(obs, [prediction])
            aided = any(d.landmark_id == LANDMARK_ID for d in aided_detector.aided)
        records.append(
            {
                "distance": distance,
                "angle": angle,
                "size_px": apparent_size_px(u.camera, pose, landmark.board_corners),
                "detected": bool(good),
                "aided": aided,
                "wrong_ids": len(detections) - len(good),
                "residuals": residuals,
                "calibrated_residuals": calibrated,
            }
        )
    return records


def _aided_detector(pattern, ids):
    """A frame detector with STSF's predicted matcher, and STSF's search radius (px)."""
    from stsf_gym.estimators import estimator_settings
    from stsf_gym.estimators.frame_detector import FrameDetector

    settings = estimator_settings("stsf")
    matcher = PredictedMatcher(pattern, settings.aided_min_correlation, settings.aided_min_board_px)
    return FrameDetector(pattern, ids, matcher=matcher), settings.aided_search_px


def world_to_camera(world_from_camera: np.ndarray, points: np.ndarray) -> np.ndarray:
    """World ``points`` (n, 3) in the camera frame of ``world_from_camera``."""
    camera_from_world = np.linalg.inv(world_from_camera)
    return points @ camera_from_world[:3, :3].T + camera_from_world[:3, 3]


def _rms(records: list[dict], key: str) -> float | None:
    residuals = np.concatenate([r[key] for r in records]) if records else np.zeros((0, 2))
    return float(np.sqrt(np.mean(residuals**2))) if len(residuals) else None


def summarise_records(records: list[dict]) -> dict:
    """Detection rate, feature error (RMS per axis: the sensor's, and with the calibration's
    error as the estimators see it; median of the norm), wrong ids."""
    residuals = np.concatenate([r["residuals"] for r in records]) if records else np.zeros((0, 2))
    return {
        "views": len(records),
        "detection_rate": float(np.mean([r["detected"] for r in records])),
        "feature_rms_px": _rms(records, "residuals"),
        "calibrated_feature_rms_px": _rms(records, "calibrated_residuals"),
        "feature_median_px": float(np.median(np.linalg.norm(residuals, axis=1)))
        if len(residuals)
        else None,
        "wrong_ids_per_view": float(np.mean([r["wrong_ids"] for r in records])),
        "aided_rate_of_missed": _mean([r["aided"] for r in records if r.get("aided") is not None]),
        "rate_vs_distance": _rates(records, "distance"),
        "rate_vs_angle": _rates(records, "angle"),
    }


def _mean(values: list) -> float | None:
    return float(np.mean(values)) if values else None


def _rates(records: list[dict], key: str) -> dict[str, float]:
    values = sorted({r[key] for r in records})
    return {
        f"{v:g}": float(np.mean([r["detected"] for r in records if r[key] == v])) for v in values
    }
