"""Table I's STSF with the joint covariance: the analytic covariance of the carried distances
against a Monte-Carlo estimate of it, and the GLS fusion it gives."""

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from test_table1 import DISTANCES, NORMAL, K, synthetic_places

from stsf_gym.estimators.odometry_model import OdometryNoise
from stsf_gym.estimators.references.measurements import OdometryLeg
from stsf_gym.experiments.table1.joint import (
    carried,
    gls,
    inverse_range,
    joint_rows,
    joint_track,
    with_motions,
)

SIGMA_PX = 0.5
NOISE = OdometryNoise(slip_var_per_m=2e-6, radius_var=0.0033**2, wheelbase_var=0.01**2)
ROBOT = SimpleNamespace(calibration=SimpleNamespace(wheelbase=0.3), odometry_noise=NOISE)


def places_with_odometry():
    """The synthetic places, each leg driven in 1 cm steps: its slip covariance and its
    Jacobian by the calibration as the dead reckoning carries them."""
    places = []
    for place in synthetic_places():
        leg = OdometryLeg()
        distance = float(np.hypot(*place.motion[:2]))
        direction = np.sign(place.motion[0]) if distance else 0.0
        for _ in range(round(distance / 0.01)):
            leg.add(ROBOT, direction * 0.01, direction * 0.01)
        pose = np.array([*place.world_from_camera[:2, 3], place.heading])
        J = leg.by_calibration
        places.append(
            replace(
                place,
                pose=pose,
                motion_by_calibration=J,
                motion_cov=leg.cov + J @ NOISE.calibration_cov @ J.T,
            )
        )
    return places


@pytest.mark.slow
def test_joint_covariance_matches_monte_carlo():
    places = places_with_odometry()
    k = len(places) - 1
    measured = list(range(1, k + 1))
    args = (K, NORMAL, SIGMA_PX, 0.0)
    _, sigma = inverse_range(*joint_track(places, k, measured, *args, NOISE.calibration_cov))
    rng = np.random.default_rng(7)
    motions = np.array([p.motion for p in places])
    draws = []
    for _ in range(400):
        c = rng.multivariate_normal(np.zeros(3), NOISE.calibration_cov)
        slip = [
            rng.multivariate_normal(
                np.zeros(3),
                p.motion_cov
                - p.motion_by_calibration @ NOISE.calibration_cov @ p.motion_by_calibration.T,
            )
            for p in places
        ]
        errors = np.array([p.motion_by_calibration @ c for p in places]) + np.array(slip)
        noisy = [
            replace(
                p,
                points={
                    i: q + rng.normal(0, SIGMA_PX / np.sqrt(p.frames), 2)
                    for i, q in p.points.items()
                },
            )
            for p in with_motions(places, motions + errors)
        ]
        draws.append(1.0 / carried(noisy, k, measured, *args))
    empirical = np.cov(np.array(draws).T)
    scale = np.sqrt(np.diag(sigma))
    assert np.all(np.abs(np.diag(empirical) / np.diag(sigma) - 1) < 0.25)
    correlation = sigma / np.outer(scale, scale)
    assert np.max(np.abs(empirical / np.outer(scale, scale) - correlation)) < 0.12
    assert correlation[-1, -2] > 0.5  # the shared calibration correlates the rows strongly
    # the joint covariance's GLS estimate varies least among linear unbiased ones
    weights = np.linalg.solve(sigma, np.ones(k))
    weights /= weights.sum()
    assert weights @ empirical @ weights <= np.ones(k) @ empirical @ np.ones(k) / k**2
    assert empirical[-1, -1] >= weights @ empirical @ weights


@pytest.mark.slow
def test_rows_report_the_joint_fusion():
    places = places_with_odometry()
    rows = joint_rows(places, K, NORMAL, SIGMA_PX, 0.0, NOISE.calibration_cov)
    assert len(rows) == len(DISTANCES) - 1
    truth = np.array(DISTANCES[1:])
    assert np.allclose(rows, truth, atol=0.02)  # exact data: the true distances
    assert np.isclose(gls(np.array([1.0, 2.0]), np.diag([1.0, 4.0])), (1.0 + 2.0 / 4) / (1 + 1 / 4))
