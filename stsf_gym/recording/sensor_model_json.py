"""The robot's :class:`~stsf_gym.estimators.base.SensorModel` as JSON, and back, exactly.

A log carries the model an estimator runs on as one JSON document (the ``/robot/sensor_model``
topic, :mod:`stsf_gym.recording.topics`). Every number is a float64 (or int) written with
Python's shortest round-trip repr, so a model read back is the recorded one bit for bit::

    {"format": "stsf-gym sensor model", "version": 1,
     "odometry": {"ticks_per_rev", "wheel_radius_left", "wheel_radius_right", "wheelbase"},
     "odometry_noise": {"slip_var_per_m", "radius_var", "wheelbase_var"},
     "camera": {"K": 3x3, "dist": [k1, k2, p1, p2, k3], "image_size": [width, height],
                "calibration_std": [principal point as heading (rad), focal (relative)]},
     "mount": {"x", "y", "z"},            # the pan-tilt head in the robot frame (m)
     "pattern": {"square_size", "pitch", "grid", "border"},
     "landmarks": [{"id", "centre": [x, y, z], "normal": [x, y, z],
                    "square_centres": [[x, y, z], ...]}, ...],
     "walls": [[x1, y1, x2, y2], ...]}   # the map's wall centre lines (m)

The camera is the one the robot *believes* it has (K and distortion with the episode's
calibration error), never the simulator's true camera.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from typing import Any

import numpy as np

from stsf_gym.camera_model import CameraCalibration, PanTiltMount
from stsf_gym.estimators import MapLandmark, SensorModel
from stsf_gym.estimators.odometry import OdometryNoise
from stsf_gym.geometry import OdometryCalibration
from stsf_gym.validation import ConfigError
from stsf_gym.vision.landmarks import LandmarkPattern

FORMAT, VERSION = "stsf-gym sensor model", 1


def sensor_model_dict(model: SensorModel) -> dict[str, Any]:
    """``model`` as JSON-ready values; its mount must be a :class:`PanTiltMount`."""
    mount = model.robot_from_camera
    if not isinstance(mount, PanTiltMount):
        raise TypeError(
            f"only a PanTiltMount camera mount can be recorded, got {type(mount).__name__}"
        )
    return {
        "format": FORMAT,
        "version": VERSION,
        "odometry": asdict(model.calibration),
        "odometry_noise": asdict(model.odometry_noise),
        "camera": {
            "K": np.asarray(model.camera_calibration.K, float).tolist(),
            "dist": np.asarray(model.camera_calibration.dist, float).tolist(),
            "image_size": list(model.image_size),
            "calibration_std": list(model.camera_calibration_std),
        },
        "mount": asdict(mount),
        "pattern": asdict(model.pattern),
        "landmarks": [
            {
                "id": lm.id,
                "centre": np.asarray(lm.centre, float).tolist(),
                "normal": np.asarray(lm.normal, float).tolist(),
                "square_centres": np.asarray(lm.square_centres, float).tolist(),
            }
            for lm in model.landmarks.values()
        ],
        "walls": np.asarray(model.walls, float).reshape(-1, 4).tolist(),
    }


def sensor_model_json(model: SensorModel) -> str:
    """``model`` as the JSON text of ``/robot/sensor_model`` (docs/log_format.md)."""
    return json.dumps(sensor_model_dict(model), default=lambda v: v.item())  # numpy scalars


def sensor_model_from_dict(data: dict[str, Any], where: str = "sensor model") -> SensorModel:
    """The :class:`SensorModel` of a :func:`sensor_model_dict`; a missing or malformed key is
    a :class:`ConfigError` naming it and ``where`` (the log file)."""
    if data.get("format") != FORMAT or data.get("version") != VERSION:
        raise ConfigError(
            f"{where}: not a {FORMAT!r} version {VERSION} document "
            f"(format {data.get('format')!r}, version {data.get('version')!r})"
        )
    try:
        camera = data["camera"]
        K = np.array(camera["K"], dtype=float).reshape(3, 3)
        calibration = CameraCalibration(K, np.array(camera["dist"], dtype=float).reshape(5))
        landmarks = {
            int(lm["id"]): MapLandmark(
                int(lm["id"]),
                np.array(lm["centre"], dtype=float).reshape(3),
                np.array(lm["normal"], dtype=float).reshape(3),
                np.array(lm["square_centres"], dtype=float).reshape(-1, 3),
            )
            for lm in data["landmarks"]
        }
        width, height = (int(v) for v in camera["image_size"])
        heading_std, focal_std = (float(v) for v in camera["calibration_std"])
        return SensorModel(
            calibration=OdometryCalibration(**data["odometry"]),
            odometry_noise=OdometryNoise(**data["odometry_noise"]),
            camera_calibration=calibration,
            camera_calibration_std=(heading_std, focal_std),
            camera_matrix=K,
            image_size=(width, height),
            robot_from_camera=PanTiltMount(**data["mount"]),
            landmarks=landmarks,
            pattern=LandmarkPattern(**data["pattern"]),
            walls=np.array(data["walls"], dtype=float).reshape(-1, 4),
        )
    except KeyError as err:
        raise ConfigError(f"{where}: missing key {err.args[0]!r}") from None
    except (TypeError, ValueError) as err:
        raise ConfigError(f"{where}: {err}") from None
