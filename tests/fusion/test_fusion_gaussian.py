"""Eq. 21-24: covariance from principal axes and the Smith & Cheeseman merge."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stsf_gym.fusion import covariance_from_axes, merge_gaussians

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)


def _spd(rng: np.random.Generator, m: int) -> np.ndarray:
    a = rng.normal(size=(m, m))
    return a @ a.T + 0.05 * np.eye(m)


@given(st.floats(0.01, 5.0), st.floats(0.1, 0.9), st.floats(-np.pi, np.pi))
@FAST
def test_covariance_major_axis_points_along_theta(sigma_max, ratio, theta):
    sigma_min = ratio * sigma_max
    cov = covariance_from_axes(sigma_max, sigma_min, theta)
    values, vectors = np.linalg.eigh(cov)
    np.testing.assert_allclose(values, [sigma_min**2, sigma_max**2], rtol=1e-9)
    major = vectors[:, 1]
    assert abs(major @ [np.cos(theta), np.sin(theta)]) == pytest.approx(1.0, abs=1e-9)


def test_covariance_from_axes_rejects_swapped_axes():
    with pytest.raises(ValueError, match="sigma_min"):
        covariance_from_axes(0.1, 0.2, 0.0)


@given(SEEDS, st.integers(1, 4))
@FAST
def test_merge_is_a_kalman_update_with_identity_measurement(seed, m):
    rng = np.random.default_rng(seed)
    x1, x2 = rng.normal(size=(2, m))
    c1, c2 = _spd(rng, m), _spd(rng, m)
    x, cov = merge_gaussians(x1, c1, x2, c2)
    gain = c1 @ np.linalg.inv(c1 + c2)  # H = I, measurement x2 with noise c2
    np.testing.assert_allclose(x, x1 + gain @ (x2 - x1), rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(cov, (np.eye(m) - gain) @ c1, rtol=1e-8, atol=1e-10)
    np.testing.assert_array_equal(cov, cov.T)


@given(SEEDS)
@FAST
def test_merge_is_symmetric_in_its_arguments(seed):
    rng = np.random.default_rng(seed)
    x1, x2 = rng.normal(size=(2, 3))
    c1, c2 = _spd(rng, 3), _spd(rng, 3)
    xa, ca = merge_gaussians(x1, c1, x2, c2, angle_index=[2])
    xb, cb = merge_gaussians(x2, c2, x1, c1, angle_index=[2])
    np.testing.assert_allclose(xa, xb, atol=1e-9)
    np.testing.assert_allclose(ca, cb, atol=1e-9)


def test_pose_merge_wraps_the_heading():
    cov = np.diag([0.01, 0.01, 0.01])
    x, _ = merge_gaussians([1.0, 0.0, np.pi - 0.1], cov, [1.0, 0.0, -np.pi + 0.1], cov, [2])
    assert abs(abs(x[2]) - np.pi) < 1e-12  # not 0, the naive average
    x, _ = merge_gaussians([0, 0, np.pi - 0.1], cov, [0, 0, -np.pi + 0.3], cov, [2])
    assert x[2] == pytest.approx(-np.pi + 0.1)


def test_scalar_merge_and_shape_errors():
    x, var = merge_gaussians(1.0, 1.0, 3.0, 1.0)
    np.testing.assert_allclose([x[0], var[0, 0]], [2.0, 0.5])
    with pytest.raises(ValueError, match="shapes"):
        merge_gaussians(np.zeros(2), np.eye(2), np.zeros(3), np.eye(3))
