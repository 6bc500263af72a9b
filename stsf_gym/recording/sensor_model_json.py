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
from dataclasses import asdict, dataclass
from typing import Annotated, Any

import numpy as np

from stsf_gym.camera_model import CameraCalibration, PanTiltMount
from stsf_gym.estimators import MapLandmark, SensorModel
from stsf_gym.estimators.odometry_model import OdometryNoise
from stsf_gym.geometry import OdometryCalibration
from stsf_gym.validation import (
    ConfigError,
    Coordinate,
    NonNegative,
    Pixels,
    Range,
    build,
    require,
)
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


Vector3 = tuple[float, float, float]
Point3 = tuple[Coordinate, Coordinate, Coordinate]


@dataclass(frozen=True)
class CameraDocument:
    """``camera``: the believed intrinsics, distortion, image size and calibration doubt."""

    K: tuple[Vector3, Vector3, Vector3]
    dist: tuple[float, float, float, float, float]
    image_size: tuple[Pixels, Pixels]
    calibration_std: tuple[NonNegative, NonNegative]

    def __post_init__(self) -> None:
        (fx, _, _), (zero, fy, _), bottom = self.K
        require(fx > 0 and fy > 0, "K", f"must have focal lengths > 0, got {fx}, {fy}")
        require(zero == 0 and bottom == (0, 0, 1), "K", f"must be a pinhole matrix, got {self.K}")


@dataclass(frozen=True)
class LandmarkDocument:
    """One board of the map: its id, centre, unit outward normal and square centres."""

    id: Annotated[int, Range(ge=0)]
    centre: Point3
    normal: Vector3
    square_centres: tuple[Point3, ...]

    def __post_init__(self) -> None:
        length = float(np.linalg.norm(self.normal))
        require(abs(length - 1) <= 1e-6, "normal", f"must be a unit vector, got {self.normal}")


@dataclass(frozen=True)
class SensorModelDocument:
    """The sensor model's JSON, each number typed and ranged as a config's
    (:mod:`stsf_gym.validation`): a log is input."""

    format: str
    version: int
    odometry: OdometryCalibration
    odometry_noise: OdometryNoise
    camera: CameraDocument
    mount: PanTiltMount
    pattern: LandmarkPattern
    landmarks: tuple[LandmarkDocument, ...]
    walls: tuple[tuple[Coordinate, Coordinate, Coordinate, Coordinate], ...]

    def __post_init__(self) -> None:
        ids = [lm.id for lm in self.landmarks]
        require(len(set(ids)) == len(ids), "landmarks", f"must have distinct ids, got {ids}")


def sensor_model_from_dict(data: dict[str, Any], where: str = "sensor model") -> SensorModel:
    """The :class:`SensorModel` of a :func:`sensor_model_dict`; a missing, malformed or
    out-of-range key is a :class:`ConfigError` naming it and ``where`` (the log file)."""
    if not isinstance(data, dict) or (data.get("format"), data.get("version")) != (FORMAT, VERSION):
        found = (data.get("format"), data.get("version")) if isinstance(data, dict) else data
        raise ConfigError(
            f"{where}: not a {FORMAT!r} version {VERSION} document (format, version: {found})"
        )
    try:
        doc = build(SensorModelDocument, data, "")
    except ConfigError as err:
        raise ConfigError(err.message, err.key, where) from None
    camera = doc.camera
    K = np.array(camera.K, dtype=float)
    return SensorModel(
        calibration=doc.odometry,
        odometry_noise=doc.odometry_noise,
        camera_calibration=CameraCalibration(K, np.array(camera.dist, dtype=float)),
        camera_calibration_std=camera.calibration_std,
        camera_matrix=K,
        image_size=camera.image_size,
        robot_from_camera=doc.mount,
        landmarks={
            lm.id: MapLandmark(
                lm.id,
                np.array(lm.centre, dtype=float),
                np.array(lm.normal, dtype=float),
                np.array(lm.square_centres, dtype=float).reshape(-1, 3),
            )
            for lm in doc.landmarks
        },
        pattern=doc.pattern,
        walls=np.array(doc.walls, dtype=float).reshape(-1, 4),
    )
