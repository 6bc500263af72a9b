"""Table I's two measurements of the distance to a landmark from the places it was seen from.

A :class:`Place` holds what the robot knows when it stands at one place: the landmark's square
centres averaged over the place's frames, the camera pose it believes (odometry and mount), and
the odometry motion since the previous place with its covariance. Places ``0..n`` give rows
``1..n``:

- conventional fusion, row ``k``: motion stereo (eq. 8-20) between places ``k-1`` and ``k``;
- STSF, row ``k``: the motion-stereo distances of rows ``1..k``, each carried to place ``k`` by
  the odometry between the places (eq. 3, its uncertainty propagated) and fused (eq. 2) in
  inverse range with the significance weights of eq. 4-5 (and, for comparison, generalised
  least squares). Row 1 has one measurement, so both methods give the same distance.
- STSF with the joint covariance (``stsf_joint``): the same carried distances, fused by
  generalised least squares with the covariance the shared wheel calibration gives them
  (:mod:`~stsf_gym.experiments.table1.joint`): the best linear unbiased distance.

Distances are to the landmark's plane (eq. 10), from the camera of the place.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from stsf_gym.estimators.pair_range import matched_rays, pair_range
from stsf_gym.fusion import stsf_fuse, to_inverse_range, transform_range_track
from stsf_gym.geometry import to_se3

STSF_METHODS = ("significance", "gls")


@dataclass
class Place:
    """What the robot has at one place (pixels undistorted with its believed calibration)."""

    points: dict[int, np.ndarray]  # square index -> pixel, averaged over the place's frames
    frames: int  # frames averaged
    world_from_camera: np.ndarray  # 4x4, believed: odometry pose and mount
    heading: float  # odometry heading (rad)
    motion: np.ndarray  # odometry motion [x, y, yaw] since the previous place, in its robot frame
    motion_cov: np.ndarray  # its 3x3 covariance
    pose: np.ndarray | None = None  # the odometry pose [x, y, yaw] (None: not kept)
    motion_by_calibration: np.ndarray | None = None  # d motion / d wheel calibration (3x3)


def average_features(frames: list[dict[int, np.ndarray]]) -> dict[int, np.ndarray]:
    """Each square's pixel averaged over the frames that found it in at least half of them."""
    indices = {i for points in frames for i in points}
    averaged = {}
    for i in sorted(indices):
        seen = [points[i] for points in frames if i in points]
        if 2 * len(seen) >= len(frames):
            averaged[i] = np.mean(seen, axis=0)
    return averaged


def pair_distance(
    a: Place, b: Place, camera_matrix: np.ndarray, normal: np.ndarray, sigma_px: float
) -> tuple[float, float] | None:
    """Plane distance from place ``b``'s camera and its variance by motion stereo with place
    ``a`` (eq. 8-20), or ``None``. ``normal``: the board's outward normal (world);
    ``sigma_px``: one frame's feature noise, averaged over the place's frames."""
    rotation = b.world_from_camera[:3, :3]
    frames = min(a.frames, b.frames)
    rays = matched_rays(a.points, b.points, camera_matrix)
    if rays is None:
        return None
    return pair_range(
        rays,
        np.linalg.inv(a.world_from_camera) @ b.world_from_camera,
        rotation.T @ -normal,  # towards the plane, in camera-b axes
        b.motion_cov,
        rotation.T @ to_se3(np.array([0.0, 0.0, b.heading]))[:3, :3],
        sigma_px / math.sqrt(max(frames, 1)),
    )


def range_step(
    a: Place, b: Place, normal: np.ndarray, camera_forward: float
) -> tuple[float, float]:
    """Change of the camera's plane distance from place ``a`` to ``b`` by odometry, and its
    variance: ``n . (camera at b - camera at a)`` with the motion in ``a``'s robot frame."""
    u, Q = b.motion, b.motion_cov
    heading = to_se3(np.array([0.0, 0.0, a.heading]))[:2, :2]
    n = heading.T @ normal[:2]  # the normal in a's robot frame
    c = camera_forward
    moved = u[:2] + c * np.array([math.cos(u[2]), math.sin(u[2])]) - (c, 0.0)
    gradient = np.array([n[0], n[1], c * (n[1] * math.cos(u[2]) - n[0] * math.sin(u[2]))])
    return float(n @ moved), float(gradient @ Q @ gradient)


def stsf_distance(
    distances: list[float], variances: list[float], steps: list[float], step_variances: list[float]
) -> dict[str, float]:
    """Eq. 2-5 over a range track (measurement ``j`` carried by ``steps[j:]``), in inverse range,
    by each of :data:`STSF_METHODS`."""
    rho, cov = to_inverse_range(*transform_range_track(distances, variances, steps, step_variances))
    return {m: 1.0 / float(stsf_fuse(rho, cov, method=m).x[0]) for m in STSF_METHODS}


def measure_rows(
    places: list[Place],
    camera_matrix: np.ndarray,
    normal: np.ndarray,
    sigma_px: float,
    camera_forward: float,
) -> dict[str, list[float]]:
    """Per row ``k = 1..len(places)-1``: ``conventional`` (pair k-1, k), its ``variance``,
    ``stsf`` and ``stsf_gls`` (rows 1..k fused); NaN where a pair gave no distance (STSF then
    fuses the rows that did)."""
    rows: dict[str, list[float]] = {"conventional": [], "variance": [], "stsf": [], "stsf_gls": []}
    track: list[tuple[float, float, int]] = []  # (distance, variance, place) per measurement
    for k in range(1, len(places)):
        measured = pair_distance(places[k - 1], places[k], camera_matrix, normal, sigma_px)
        if measured is not None:
            track.append((*measured, k))
        distance, variance = measured if measured is not None else (math.nan, math.nan)
        rows["conventional"].append(distance)
        rows["variance"].append(variance)
        fused = {m: math.nan for m in STSF_METHODS}
        if track:
            at = [j for *_, j in track]
            steps = [_odometry_step(places, i, j, normal, camera_forward) for i, j in pairwise(at)]
            fused = stsf_distance(
                [t[0] for t in track],
                [t[1] for t in track],
                [s[0] for s in steps],
                [s[1] for s in steps],
            )
            rest = _odometry_step(places, at[-1], k, normal, camera_forward)[0]
            fused = {m: d + rest for m, d in fused.items()}  # carried on to place k
        rows["stsf"].append(fused["significance"])
        rows["stsf_gls"].append(fused["gls"])
    return rows


def _odometry_step(
    places: list[Place], i: int, j: int, normal: np.ndarray, camera_forward: float
) -> tuple[float, float]:
    """Odometry's change of the plane distance from place ``i`` to place ``j`` and its variance
    (the legs between the places in between add up)."""
    legs = [
        range_step(places[m - 1], places[m], normal, camera_forward) for m in range(i + 1, j + 1)
    ]
    return float(sum(s for s, _ in legs)), float(sum(v for _, v in legs))
