"""Eq. 1: conventional spatial fusion and its minimum-variance weights."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stsf_gym.fusion import merge_gaussians, spatial_fusion

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)


def _spd(rng: np.random.Generator, n: int, m: int) -> np.ndarray:
    a = rng.normal(size=(n, m, m))
    return a @ np.swapaxes(a, 1, 2) + 0.1 * np.eye(m)


def _min_eig(matrix: np.ndarray) -> float:
    return float(np.linalg.eigvalsh(0.5 * (matrix + matrix.T)).min())


def test_equal_weights_without_covariances():
    xs = np.array([[1.0, 2.0], [3.0, 6.0]])
    x, cov = spatial_fusion(xs)
    np.testing.assert_allclose(x, [2.0, 4.0])
    assert cov is None


def test_scalar_and_matrix_weights():
    xs = np.array([[1.0, 2.0], [3.0, 6.0]])
    np.testing.assert_allclose(spatial_fusion(xs, weights=[0.25, 0.75])[0], [2.5, 5.0])
    weights = np.array([np.diag([1.0, 0.0]), np.diag([0.0, 1.0])])
    x, cov = spatial_fusion(xs, weights=weights, covs=np.array([np.eye(2), 4 * np.eye(2)]))
    np.testing.assert_allclose(x, [1.0, 6.0])
    np.testing.assert_allclose(cov, np.diag([1.0, 4.0]))


@pytest.mark.parametrize(
    ("weights", "message"),
    [
        ([0.5, 0.6], "sum to 1"),
        (np.array([np.eye(2), np.eye(2)]), "sum to the identity"),
        ([1.0], "shape"),
    ],
)
def test_invalid_weights_are_rejected(weights, message):
    with pytest.raises(ValueError, match=message):
        spatial_fusion(np.zeros((2, 2)), weights=weights)


def test_invalid_shapes_are_rejected():
    with pytest.raises(ValueError, match="shape"):
        spatial_fusion(np.zeros(3))
    with pytest.raises(ValueError, match="covs"):
        spatial_fusion(np.zeros((2, 2)), covs=np.zeros((2, 3, 3)))


@given(SEEDS, st.integers(2, 5), st.integers(1, 3))
@FAST
def test_inverse_variance_weights_give_the_minimum_variance(seed, n, m):
    rng = np.random.default_rng(seed)
    covs, xs = _spd(rng, n, m), rng.normal(size=(n, m))
    x, cov = spatial_fusion(xs, covs=covs)
    information = np.linalg.inv(covs).sum(axis=0)
    np.testing.assert_allclose(cov, np.linalg.inv(information), rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(
        x,
        np.linalg.solve(information, np.einsum("iab,ib->a", np.linalg.inv(covs), xs)),
        rtol=1e-8,
        atol=1e-10,
    )
    scalar = rng.dirichlet(np.ones(n))
    matrices = rng.normal(size=(n, m, m))
    matrices[-1] = np.eye(m) - matrices[:-1].sum(axis=0)
    for weights in (scalar, matrices):
        _, other = spatial_fusion(xs, weights=weights, covs=covs)
        assert _min_eig(other - cov) >= -1e-9 * np.abs(other).max()


def test_two_sensors_agree_with_gaussian_merge():
    rng = np.random.default_rng(7)
    covs, xs = _spd(rng, 2, 3), rng.normal(size=(2, 3))
    x, cov = spatial_fusion(xs, covs=covs)
    x_merge, cov_merge = merge_gaussians(xs[0], covs[0], xs[1], covs[1])
    np.testing.assert_allclose(x, x_merge, atol=1e-12)
    np.testing.assert_allclose(cov, cov_merge, atol=1e-12)
