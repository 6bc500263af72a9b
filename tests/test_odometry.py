import numpy as np
import pytest

from stsf_gym.estimators.odometry import OdometryNoise, integrate_wheel_travel, propagate


def test_straight_and_turn_in_place():
    pose = integrate_wheel_travel(np.zeros(3), 1.0, 1.0, 0.4)
    np.testing.assert_allclose(pose, [1.0, 0.0, 0.0])
    pose = integrate_wheel_travel(np.zeros(3), -0.1 * np.pi, 0.1 * np.pi, 0.4)
    np.testing.assert_allclose(pose, [0.0, 0.0, np.pi / 2], atol=1e-12)


def test_propagated_covariance_matches_monte_carlo():
    """NEES of sampled dead-reckoning errors averages the state dimension (3)."""
    noise = OdometryNoise(slip_var_per_m=2e-5, radius_var=1e-5, calibration_length=2.0)
    wheelbase, rng = 0.4, np.random.default_rng(0)
    travels = [(0.012, 0.012)] * 80 + [(0.008, 0.016)] * 40 + [(0.015, 0.010)] * 60
    mean, cov = np.zeros(3), np.zeros((3, 3))
    for d_left, d_right in travels:
        mean, cov = propagate(mean, cov, d_left, d_right, wheelbase, noise)
    samples = np.zeros((2000, 3))
    for d_left, d_right in travels:
        std = np.sqrt(noise.random_walk_variances(d_left, d_right))
        d = np.array([d_left, d_right]) + rng.standard_normal((len(samples), 2)) * std
        samples = np.array(
            [integrate_wheel_travel(p, *w, wheelbase) for p, w in zip(samples, d, strict=True)]
        )
    errors = samples - mean
    nees = np.einsum("ni,ij,nj->n", errors, np.linalg.inv(cov), errors)
    assert nees.mean() == pytest.approx(3.0, rel=0.1)
    assert np.all(np.abs(errors.mean(axis=0)) < 4 * np.sqrt(np.diag(cov) / len(samples)))
