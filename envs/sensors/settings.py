"""The sensors' config sections (``camera:``, ``sonar:``, ``encoders:`` of the env config):
typed, ranged, and checked where one value bounds another (a lens must not fold the image over,
the sonar's ranges and firing order). :mod:`stsf_gym.envs.config` assembles them."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np

from stsf_gym.camera_model import invertible
from stsf_gym.validation import (
    Count,
    Degrees,
    NonNegative,
    Pixels,
    Positive,
    Probability,
    Range,
    require,
)


@dataclass(frozen=True)
class FastCameraConfig:
    """Statistics of the detector, fitted on rendered frames (``benchmarks/fast_sensor_fit.py``)."""

    feature_noise_px: NonNegative  # std of each square centre's pixel error, per axis
    detect_size_px: Positive  # square pitch (px) at which half of the boards are detected
    detect_size_scale: Positive  # logistic width of the detection rate in square pitch (px)
    false_detection_rate: NonNegative  # wrong-id detections per frame
    aided_size_px: Positive  # size (px) at which a track-aided search finds half the missed boards
    aided_size_scale: Positive  # logistic width of that rate (px)
    max_detections: Count  # detection slots in the observation


Relative = Annotated[float, Range(ge=0, lt=0.5)]


@dataclass(frozen=True)
class LensConfig:
    """The lens (:mod:`stsf_gym.envs.sensors.lens`): distortion, vignetting and defocus."""

    distortion: tuple[float, float, float, float, float]  # OpenCV k1 k2 p1 p2 k3
    vignetting: Annotated[float, Range(ge=0, lt=1)]  # share of light lost at the image corner
    defocus_px: NonNegative  # std (px) of the lens's Gaussian point spread; 0 in focus


def radial_reach(distortion: tuple[float, ...], limit: float = 10.0) -> float:
    """The largest distorted radius (normalised image coordinates) that the radial part of
    ``distortion`` (OpenCV k1 k2 p1 p2 k3) reaches while it still grows with the ray's
    radius: the image is invertible up to there. ``limit`` for a lens that never stops."""
    k1, k2, _, _, k3 = distortion
    r = np.linspace(0.0, limit, 20001)
    slope = 1 + 3 * k1 * r**2 + 5 * k2 * r**4 + 7 * k3 * r**6
    stop = int(np.argmax(slope <= 0)) if (slope <= 0).any() else r.size - 1
    radius = r[: stop + 1]
    return float(np.max(radius * (1 + k1 * radius**2 + k2 * radius**4 + k3 * radius**6)))


@dataclass(frozen=True)
class SensorConfig:
    """The image sensor (:mod:`stsf_gym.envs.sensors.image_sensor`): exposure and noise."""

    exposure_s: NonNegative  # exposure time: the camera's motion during it blurs the frame
    gain_std: Relative  # per-frame exposure/gain variation, relative
    read_noise: Annotated[float, Range(ge=0, le=255)]  # std, grey levels
    shot_noise: NonNegative  # photon noise: variance (grey levels^2) per grey level of signal


@dataclass(frozen=True)
class CalibrationErrorConfig:
    """How far the robot's believed camera calibration is from the truth, drawn per episode."""

    focal_std: Relative  # relative error of the focal length
    principal_point_std_px: NonNegative
    distortion_std: tuple[NonNegative, NonNegative, NonNegative, NonNegative, NonNegative]


@dataclass(frozen=True)
class LatencyConfig:
    """Exposure to availability of a camera frame (``configs/latency/<profile>.yaml``)."""

    profile: str  # zero | paper | any file of configs/latency
    delay_s: NonNegative  # s from a frame's exposure until the robot has its result
    jitter_s: NonNegative  # s, std of a half-normal extra delay per frame


@dataclass(frozen=True)
class CameraConfig:
    """The camera (``camera:``): image, rate, mount control, sensor mode, profile, latency."""

    enabled: bool
    width: Pixels
    height: Pixels
    vfov_deg: Annotated[float, Range(gt=0, lt=180)]
    rate_hz: Positive
    near: Positive
    far: Positive
    renderer: Literal["auto", "gl", "egl", "tiny"]
    pan_deg: Degrees
    tilt_deg: Degrees
    control: Literal["none", "pan", "pan_tilt"]
    profile: str  # configs/cameras/<profile>.yaml: lens, sensor, calibration_error
    lens: LensConfig
    sensor: SensorConfig
    calibration_error: CalibrationErrorConfig
    feature_rms_px: Positive  # the detector's feature error the profile is made to give
    mode: Literal["rendered", "fast"]
    fast: FastCameraConfig
    latency: LatencyConfig

    def __post_init__(self) -> None:
        require(self.far > self.near, "far", f"must be > near ({self.near}), got {self.far}")
        corner = math.hypot(self.width, self.height) / self.height  # normalised corner radius
        corner *= math.tan(math.radians(self.vfov_deg) / 2)
        reach = radial_reach(self.lens.distortion)
        require(
            reach > corner,
            "lens.distortion",
            f"{list(self.lens.distortion)} folds the image over: its radial mapping "
            f"r(1 + k1 r^2 + k2 r^4 + k3 r^6) stops growing at distorted radius {reach:.3g}, "
            f"inside the image corner at {corner:.3g} (a lens maps each ray to one pixel)",
        )
        require(
            not any(self.lens.distortion) or invertible(self.lens.distortion, corner),
            "lens.distortion",
            f"{list(self.lens.distortion)} cannot be undone: the undistortion every estimator "
            f"runs (stsf_gym.camera_model.undistort) does not find the rays of the image out to "
            f"its corner at {corner:.3g} (the coefficients are too strong for a real lens)",
        )


@dataclass(frozen=True)
class SonarBeamConfig:
    """The sonar beam model (:mod:`stsf_gym.envs.sensors.sonar_beam`), off by default."""

    enabled: bool
    critical_angle_deg: Annotated[float, Range(gt=0, le=90)]  # incidence at half detection
    angle_width_deg: Annotated[float, Range(gt=0, le=90)]  # how sharply detection falls
    random_prob: Probability  # a reading uniform in [min_range, max_range]
    crosstalk_prob: Probability  # a neighbour's echo (a ring firing all together)


@dataclass(frozen=True)
class SonarConfig:
    """The sonar ring (``sonar:``): transducers, cones, ranges, noise and firing order."""

    count: Count
    beam_width_deg: Annotated[float, Range(gt=0, le=360)]
    rays_per_beam: Count
    height: NonNegative
    min_range: NonNegative
    max_range: Positive
    noise_std: NonNegative
    noise_std_per_m: NonNegative
    dropout_prob: Probability
    firing_order: tuple[int, ...]  # transducers in firing order; empty: all fire at each step end
    firing_interval_s: NonNegative  # s between consecutive firings of the order
    beam: SonarBeamConfig
    cast: Literal["bullet", "plane"] = "plane"  # rays in the ring's plane, or through PyBullet

    def __post_init__(self) -> None:
        require(
            self.max_range > self.min_range,
            "max_range",
            f"must be > min_range ({self.min_range}), got {self.max_range}",
        )
        order = self.firing_order
        require(
            all(0 <= t < self.count for t in order) and len(set(order)) == len(order),
            "firing_order",
            f"must list distinct transducers of 0..{self.count - 1}, got {list(order)}",
        )
        require(
            not order or self.firing_interval_s > 0,
            "firing_interval_s",
            f"must be > 0 with a firing_order, got {self.firing_interval_s}",
        )


@dataclass(frozen=True)
class EncoderConfig:
    """The wheel encoders (``encoders:``): resolution, calibration errors and slip."""

    ticks_per_rev: Count
    radius_error_std: Annotated[float, Range(ge=0, lt=1)]  # relative
    wheelbase_error_std: Annotated[float, Range(ge=0, lt=1)]  # relative
    slip_std: NonNegative
