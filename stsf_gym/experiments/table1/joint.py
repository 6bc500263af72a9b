"""STSF's distance with the places' joint covariance: the best linear unbiased fusion.

The rows' motion-stereo distances are not independent: every leg's odometry is turned and
scaled by the *same* wheel calibration ``c`` (the robot cannot know it), so each place's
believed heading, the baselines and the odometry steps that carry a distance to the latest
place share one error. Place ``m``'s odometry motion error is ``e_m = J_m c + w_m``
(``J_m`` its Jacobian by ``c``, carried by the dead reckoning, :class:`Place`'s
``motion_by_calibration``; ``w_m`` the slip, independent), so the motions' joint covariance is::

    C_u = blockdiag(Q_m - J_m Sigma_c J_m^T) + J Sigma_c J^T,   J = [J_0; ...; J_n]

For row ``k`` the carried distances ``t_j = D_j + sum_{m=j+1..k} step_m`` (the motion-stereo
distance of pair ``(j-1, j)`` carried by odometry to place ``k``, eq. 3) are functions of the
features and of every motion ``u`` (each place's believed pose is the start composed with
the motions up to it). Their joint covariance::

    Sigma = sum_p G_p (sigma_px^2 / frames_p) G_p^T + G C_u G^T,   G = dt/du,  G_p = dt/dq_p

(central differences; ``q_p`` the averaged square centres of place ``p``, which enter both
pair ``(p-1, p)`` and pair ``(p, p+1)``: consecutive rows share them). In inverse range
``rho_j = 1 / t_j`` (where the motion-stereo errors are nearly Gaussian, as STSF fuses), the
generalised least squares weights ``w = Sigma_rho^-1 1 / (1^T Sigma_rho^-1 1)`` give the best
linear unbiased ``w^T rho`` from rows ``1..k`` (Aitken 1935): no weighting of these
measurements is better on average.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from stsf_gym.experiments.table1.measure import Place, pair_distance, range_step
from stsf_gym.geometry import compose, inverse, to_se3

STEP = 1e-6  # m and rad: central-difference step on a motion
PIXEL_STEP = 1e-3  # px: central-difference step on a feature


def carried(
    places: list[Place],
    k: int,
    measured: list[int],
    camera_matrix: np.ndarray,
    normal: np.ndarray,
    sigma_px: float,
    camera_forward: float,
) -> np.ndarray:
    """``t_j`` for the places ``j`` in ``measured`` (each ``<= k``): pair ``(j-1, j)``'s
    distance carried by odometry to place ``k``."""
    steps = [0.0] + [
        range_step(places[m - 1], places[m], normal, camera_forward)[0] for m in range(1, k + 1)
    ]
    values = []
    for j in measured:
        distance = pair_distance(places[j - 1], places[j], camera_matrix, normal, sigma_px)
        values.append(np.nan if distance is None else distance[0] + sum(steps[j + 1 : k + 1]))
    return np.array(values)


def with_motions(places: list[Place], motions: np.ndarray) -> list[Place]:
    """The places as the robot would believe them with these odometry motions: each pose the
    start composed with the motions up to it, the camera mount and features unchanged."""
    start = compose(places[0].pose, inverse(places[0].motion))
    moved, pose = [], start
    for place, motion in zip(places, motions, strict=True):
        mount = np.linalg.inv(to_se3(place.pose)) @ place.world_from_camera
        pose = compose(pose, motion)
        world_from_camera = to_se3(pose) @ mount
        moved.append(
            replace(
                place,
                pose=pose,
                heading=float(pose[2]),
                motion=motion,
                world_from_camera=world_from_camera,
            )
        )
    return moved


def motion_covariance(places: list[Place], calibration_cov: np.ndarray) -> np.ndarray:
    """``C_u``: the joint covariance of every place's odometry motion."""
    J = np.vstack([p.motion_by_calibration for p in places])
    shared = J @ calibration_cov @ J.T
    slip = np.zeros_like(shared)
    for m, place in enumerate(places):
        own = place.motion_by_calibration @ calibration_cov @ place.motion_by_calibration.T
        slip[3 * m : 3 * m + 3, 3 * m : 3 * m + 3] = place.motion_cov - own
    return shared + slip


def joint_track(
    places: list[Place],
    k: int,
    measured: list[int],
    camera_matrix: np.ndarray,
    normal: np.ndarray,
    sigma_px: float,
    camera_forward: float,
    calibration_cov: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``t`` and its joint covariance ``Sigma`` for row ``k``."""
    args = (camera_matrix, normal, sigma_px, camera_forward)
    t = carried(places, k, measured, *args)
    motions = np.array([p.motion for p in places])
    G = np.zeros((len(measured), motions.size))
    for i in range(motions.size):
        step = np.zeros(motions.size)
        step[i] = STEP
        ahead = carried(
            with_motions(places, motions + step.reshape(motions.shape)), k, measured, *args
        )
        behind = carried(
            with_motions(places, motions - step.reshape(motions.shape)), k, measured, *args
        )
        G[:, i] = (ahead - behind) / (2 * STEP)
    sigma = pixel_covariance(places, k, measured, *args)
    sigma += G @ motion_covariance(places, calibration_cov) @ G.T
    return t, 0.5 * (sigma + sigma.T)


def pixel_covariance(
    places: list[Place],
    k: int,
    measured: list[int],
    camera_matrix: np.ndarray,
    normal: np.ndarray,
    sigma_px: float,
    camera_forward: float,
) -> np.ndarray:
    """The features' share of ``Sigma``: each place's averaged square centres (std
    ``sigma_px / sqrt(frames)`` per coordinate) enter the pair before it and the pair after it,
    so consecutive rows share them. (Odometry steps do not depend on features: ``dt_j/dq`` is
    pair ``j``'s ``dD_j/dq``.)"""
    gradients = []  # per measured pair: {(place, square, axis): dD/dq}
    for j in measured:
        pair, gradient = [places[j - 1], places[j]], {}
        for side, place in enumerate(pair):
            for index, pixel in place.points.items():
                for axis in range(2):
                    shifted = []
                    for sign in (1, -1):
                        moved = pixel.copy()
                        moved[axis] += sign * PIXEL_STEP
                        changed = [*pair]
                        changed[side] = replace(place, points={**place.points, index: moved})
                        found = pair_distance(*changed, camera_matrix, normal, sigma_px)
                        shifted.append(np.nan if found is None else found[0])
                    key = (j - 1 + side, index, axis)
                    gradient[key] = (shifted[0] - shifted[1]) / (2 * PIXEL_STEP)
        gradients.append(gradient)
    sigma = np.zeros((len(measured), len(measured)))
    for a, first in enumerate(gradients):
        for b, second in enumerate(gradients):
            sigma[a, b] = sum(
                sigma_px**2 / max(places[key[0]].frames, 1) * value * second[key]
                for key, value in first.items()
                if key in second
            )
    return sigma


def inverse_range(t: np.ndarray, sigma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``rho = 1 / t`` and its covariance (first order), where motion-stereo errors are nearly
    Gaussian (:func:`~stsf_gym.fusion.to_inverse_range`)."""
    jac = -1.0 / t**2
    return 1.0 / t, sigma * np.outer(jac, jac)


def gls(values: np.ndarray, sigma: np.ndarray) -> float:
    """The best linear unbiased estimate of one quantity measured ``values`` (covariance
    ``sigma``): ``w^T values`` with ``w = Sigma^-1 1 / (1^T Sigma^-1 1)``."""
    ones = np.ones(len(values))
    weights = np.linalg.solve(sigma, ones)
    return float(weights @ values / (weights @ ones))


def gls_distance(t: np.ndarray, sigma: np.ndarray) -> float:
    """STSF's distance with the joint covariance: GLS in inverse range, as eq. 2-5 fuse."""
    return 1.0 / gls(*inverse_range(t, sigma))


def joint_rows(
    places: list[Place],
    camera_matrix: np.ndarray,
    normal: np.ndarray,
    sigma_px: float,
    camera_forward: float,
    calibration_cov: np.ndarray,
) -> list[float]:
    """Per row ``k = 1..len(places)-1``: the distances of the pairs measured so far fused by
    :func:`gls_distance` with their joint covariance (NaN before any pair measured)."""
    args = (camera_matrix, normal, sigma_px, camera_forward)
    measured, rows = [], []
    for k in range(1, len(places)):
        if pair_distance(places[k - 1], places[k], camera_matrix, normal, sigma_px) is not None:
            measured.append(k)
        if not measured:
            rows.append(np.nan)
            continue
        rows.append(gls_distance(*joint_track(places, k, measured, *args, calibration_cov)))
    return rows
