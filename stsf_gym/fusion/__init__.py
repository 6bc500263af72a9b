"""Fusion core of stsf-gym: the paper's equations on plain numpy arrays.

- :func:`spatial_fusion` (eq. 1): conventional fusion of simultaneous measurements.
- :func:`covariance_from_axes`, :func:`merge_gaussians` (eq. 21-24): Gaussian observations.
- :func:`motion_stereo_range`, :func:`motion_stereo_variance` (both at once:
  :func:`motion_stereo_estimate`), :func:`stereo_range_bound`
  (eq. 8-20): range from two frames of one camera.
- :func:`transform_pose_track`, :func:`transform_range_track`, :class:`STSFTrack` (eq. 3)
  and :func:`stsf_fuse`, :func:`significance` (eq. 2, 4-5): STSF temporal fusion, with the
  joint covariance of a track's sets in :class:`TrackCovariance` / :class:`DenseCovariance`.
"""

from stsf_gym.fusion.covariance import DenseCovariance, TrackCovariance
from stsf_gym.fusion.gaussian import covariance_from_axes, merge_gaussians
from stsf_gym.fusion.motion_stereo import (
    DegenerateGeometryError,
    motion_stereo_estimate,
    motion_stereo_range,
    motion_stereo_variance,
    stereo_range_bound,
)
from stsf_gym.fusion.spatial import inverse_variance_weights, spatial_fusion
from stsf_gym.fusion.temporal import STSFResult, significance, stsf_fuse
from stsf_gym.fusion.track import (
    STSFTrack,
    to_inverse_range,
    transform_pose_track,
    transform_range_track,
)

__all__ = [
    "DegenerateGeometryError",
    "DenseCovariance",
    "STSFResult",
    "STSFTrack",
    "TrackCovariance",
    "covariance_from_axes",
    "inverse_variance_weights",
    "merge_gaussians",
    "motion_stereo_estimate",
    "motion_stereo_range",
    "motion_stereo_variance",
    "significance",
    "spatial_fusion",
    "stereo_range_bound",
    "stsf_fuse",
    "to_inverse_range",
    "transform_pose_track",
    "transform_range_track",
]
