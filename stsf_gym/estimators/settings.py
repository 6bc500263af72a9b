"""Estimator settings: typed, range-checked frozen dataclasses, defaults only in YAML.

``configs/estimators/<name>.yaml`` is the one source of every estimator's defaults (a file may
``extends:`` another: ``stsf.yaml`` adds the track to ``conventional.yaml``). :func:`load_settings`
merges those files and keyword overrides and builds the estimator's settings class with the
env config's machinery (:mod:`stsf_gym.validation`), so an unknown or out-of-range option
fails naming it, and the file that set it: ``stsf.max_track_frames must be >= 1, got -1``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated, Any, Literal, TypeVar

from stsf_gym.config_files import CONFIG_DIR, deep_merge, extended_files, shown
from stsf_gym.validation import (
    ConfigError,
    Count,
    KeySources,
    NonNegative,
    Positive,
    Range,
    build,
    require,
)

ESTIMATOR_DIR = CONFIG_DIR / "estimators"

OpenProbability = Annotated[float, Range(gt=0, lt=1)]
FrameCount = Annotated[int, Range(ge=0)]
Inflation = Annotated[float, Range(ge=1)]


@dataclass(frozen=True)
class OdometrySettings:
    """Dead reckoning (``odometry.yaml``), and the noise every estimator believes in: its own
    nominal values, apart from the env's true noise (``encoders`` and ``camera`` sections of
    the env config), so that a robot's model can be wrong as a real robot's is."""

    mount_std: NonNegative  # m, the camera mount's unknown position error (a camera's estimators)
    slip_std: NonNegative  # believed wheel slip, rad per sqrt(rad) of wheel rotation
    radius_error_std: NonNegative  # believed relative wheel-radius calibration error
    wheelbase_error_std: NonNegative  # believed relative wheelbase calibration error
    principal_point_std_px: NonNegative  # believed camera principal point error (px)
    focal_std: NonNegative  # believed relative focal length error


@dataclass(frozen=True)
class RelocalisationSettings:
    """The re-localisation rule shared by the landmark estimators."""

    relocalise_after: FrameCount  # rejected measurements in a row that agree; 0 = never
    relocalise_inflation: Inflation  # factor on their covariance for the restarted estimate

    def __post_init__(self) -> None:
        require(
            self.relocalise_after != 1,
            "relocalise_after",
            "must be 0 (off) or an integer >= 2, got 1",
        )


@dataclass(frozen=True)
class ConventionalSettings(RelocalisationSettings, OdometrySettings):
    """The landmark pair measurement and its use, shared by ``conventional``,
    ``conventional-filter`` and ``stsf`` (``conventional.yaml``)."""

    matching: Literal["plain", "track-aided"]  # track-aided: also search where tracks predict
    aided_min_correlation: OpenProbability  # ECC correlation a track-aided match needs
    aided_search_px: Positive  # px, radius searched around a predicted board
    aided_min_board_px: Positive  # px, smallest predicted board searched
    sigma_px: Positive
    gate_probability: OpenProbability
    max_gap_frames: FrameCount
    max_range: Positive
    min_baseline: NonNegative
    max_relative_range_std: Positive
    orientation_std_floor: NonNegative
    position_std_floor: NonNegative
    position_std_per_m: NonNegative


@dataclass(frozen=True)
class STSFSettings(ConventionalSettings):
    """STSF: conventional fusion's settings and the track's (``stsf.yaml``)."""

    weights: Literal["significance", "gls"]
    max_track_frames: Count


@dataclass(frozen=True)
class BoardMeasurementSettings(RelocalisationSettings, OdometrySettings):
    """What the board-measuring estimators share: pixel noise, gate, boards used in range."""

    sigma_px: Positive
    gate_probability: OpenProbability
    min_range: NonNegative
    max_range: Positive

    def __post_init__(self) -> None:
        super().__post_init__()
        require(
            self.min_range < self.max_range,
            "max_range",
            f"must be > min_range ({self.min_range:g}), got {self.max_range:g}",
        )


@dataclass(frozen=True)
class EKFSettings(BoardMeasurementSettings):
    """The range/bearing EKF (``ekf.yaml``)."""

    range_std_floor: NonNegative
    range_std_fraction: NonNegative
    bearing_std_floor: NonNegative


@dataclass(frozen=True)
class LandmarkPoseSettings(BoardMeasurementSettings):
    """The landmark pose measurement of the graph smoothers (:mod:`.references.measurements`)."""

    position_std_floor: NonNegative
    position_std_per_m: NonNegative
    orientation_std_floor: NonNegative


@dataclass(frozen=True)
class SmootherSettings(LandmarkPoseSettings):
    """The fixed-lag factor-graph smoother (``smoother.yaml``)."""

    window_s: Positive  # s of frames kept in the graph; older ones are marginalised
    relinearize_threshold: Positive  # iSAM2: relinearise a variable whose update exceeds this


@dataclass(frozen=True)
class MCLSettings(OdometrySettings):
    """Monte Carlo localization (``mcl.yaml``)."""

    particles: Count  # the most particles (KLD-sampling's ceiling), and the start's count
    min_particles: Count
    kld_error: Positive  # KLD-sampling: bound on the K-L divergence of the particle set
    kld_quantile: OpenProbability  # with this probability
    bin_size_xy: Positive  # m: KLD-sampling's histogram bins in x and y
    bin_size_yaw: Positive  # rad: and in heading
    alpha_slow: OpenProbability  # augmented MCL: the long-term likelihood average's rate
    alpha_fast: OpenProbability  # and the short-term one's
    update_min_d: NonNegative  # m driven between measurement updates (AMCL's update_min_d)
    update_min_a: NonNegative  # rad turned between them (update_min_a)
    board_updates: Literal["every-frame", "with-sonar"]  # every frame's boards, or only those
    resample_threshold: OpenProbability  # resample when the effective sample size falls below
    roughening: NonNegative  # Gordon's K: jitter of K E N^(-1/3) after resampling (0: none)
    odometry_inflation: Inflation  # factor on the wheel slip the particles are spread by
    sonar_std: Positive  # m, the likelihood field's Gaussian
    sonar_random: OpenProbability  # weight of a random sonar reading (z_rand)
    sonar_beams: Count  # readings used per update, evenly spread over the ring (max_beams)
    sonar_max_range: Positive  # m: longer readings are left out (AMCL's laser_max_range)
    field_resolution: Positive  # m, the likelihood field's cell
    sigma_px: Positive
    position_std_floor: NonNegative  # m, std added to a board's x and y (the smoother's)
    position_std_per_m: NonNegative  # and this fraction of its range
    orientation_std_floor: NonNegative  # rad, std added to its orientation
    landmark_outlier: OpenProbability  # likelihood floor of a board (a misread id)
    gate_probability: OpenProbability  # an unknown start is confirmed by a board inside it
    min_range: NonNegative
    max_range: Positive
    prior: Literal["start", "free-space"]  # the start pose, or uniform over the free space

    def __post_init__(self) -> None:
        require(
            self.min_particles <= self.particles,
            "min_particles",
            f"must be <= particles ({self.particles}), got {self.min_particles}",
        )
        require(
            self.alpha_slow < self.alpha_fast,
            "alpha_fast",
            f"must be > alpha_slow ({self.alpha_slow:g}), got {self.alpha_fast:g}",
        )


Settings = TypeVar("Settings")


def build_settings(
    name: str, settings_type: type[Settings], options: Mapping[str, Any]
) -> Settings:
    """``settings_type``'s own defaults with ``options`` over them (an estimator with no YAML
    file: your own); errors name the key as ``<name>.<key>``."""
    return build(settings_type, dict(options), name)


def load_settings(
    name: str,
    settings_type: type[Settings],
    options: Mapping[str, Any],
    label: str | None = None,
) -> Settings:
    """``settings_type`` from ``configs/estimators/<name>.yaml`` (and the files it extends)
    with ``options`` over them; errors name the key as ``<label>.<key>`` (``label``: ``name``)
    and its file."""
    label = label or name
    tree: dict = {}
    sources = KeySources()
    for file, data in extended_files(name, ESTIMATOR_DIR, "estimator"):
        tree = deep_merge(tree, data)
        sources.record(data, shown(file), label)
    tree = deep_merge(tree, options)
    sources.record(options, None, label)
    try:
        return build(settings_type, tree, label)
    except ConfigError as err:
        raise sources.attribute(err) from err
