"""SE(2) helpers: wrapping, composition and inverse against homogeneous matrices, Jacobians."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stsf_gym.geometry import (
    clamp,
    compose,
    compose_jacobians,
    compose_with_jacobians,
    from_homogeneous,
    inverse,
    inverse_jacobian,
    rot2,
    to_homogeneous,
    wrap_angle,
)

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)


def _poses(rng: np.random.Generator, n: int) -> np.ndarray:
    return np.column_stack([rng.uniform(-5, 5, (n, 2)), rng.uniform(-np.pi, np.pi, n)])


def _numeric_jacobian(fun, x: np.ndarray, h: float = 1e-6) -> np.ndarray:
    cols = []
    for i in range(x.size):
        step = np.zeros_like(x)
        step[i] = h
        diff = fun(x + step) - fun(x - step)
        diff[2] = wrap_angle(diff[2])
        cols.append(diff / (2 * h))
    return np.column_stack(cols)


@given(st.floats(-1e3, 1e3))
@FAST
def test_wrap_angle_range_and_equivalence(angle):
    wrapped = wrap_angle(angle)
    assert -np.pi < wrapped <= np.pi
    turns = (angle - wrapped) / (2 * np.pi)
    assert turns == pytest.approx(round(turns), abs=1e-9)


def test_wrap_angle_half_open_interval():
    np.testing.assert_allclose(wrap_angle([np.pi, -np.pi, 3 * np.pi, 0.5]), [np.pi] * 3 + [0.5])


def test_rot2_is_a_rotation():
    rot = rot2(0.3)
    np.testing.assert_allclose(rot @ rot.T, np.eye(2), atol=1e-15)
    np.testing.assert_allclose(rot @ [1.0, 0.0], [np.cos(0.3), np.sin(0.3)])
    assert rot2(np.zeros((4, 5))).shape == (4, 5, 2, 2)


@given(SEEDS)
@FAST
def test_compose_and_inverse_match_homogeneous_matrices(seed):
    a, b = _poses(np.random.default_rng(seed), 2)
    np.testing.assert_allclose(
        to_homogeneous(compose(a, b)), to_homogeneous(a) @ to_homogeneous(b), atol=1e-12
    )
    np.testing.assert_allclose(
        to_homogeneous(inverse(a)), np.linalg.inv(to_homogeneous(a)), atol=1e-12
    )
    np.testing.assert_allclose(from_homogeneous(to_homogeneous(a)), a, atol=1e-12)
    np.testing.assert_allclose(compose(inverse(a), a), np.zeros(3), atol=1e-12)


@given(SEEDS)
@FAST
def test_jacobians_match_finite_differences(seed):
    a, b = _poses(np.random.default_rng(seed), 2)
    j_a, j_b = compose_jacobians(a, b)
    np.testing.assert_allclose(j_a, _numeric_jacobian(lambda x: compose(x, b), a), atol=1e-7)
    np.testing.assert_allclose(j_b, _numeric_jacobian(lambda x: compose(a, x), b), atol=1e-7)
    np.testing.assert_allclose(inverse_jacobian(a), _numeric_jacobian(inverse, a), atol=1e-7)


def test_functions_broadcast_over_stacks():
    rng = np.random.default_rng(3)
    a, b = _poses(rng, 5), _poses(rng, 5)
    stacked = compose(a, b)
    j_a, j_b = compose_jacobians(a, b)
    for i in range(5):
        np.testing.assert_allclose(stacked[i], compose(a[i], b[i]))
        np.testing.assert_allclose(j_a[i], compose_jacobians(a[i], b[i])[0])
        np.testing.assert_allclose(j_b[i], compose_jacobians(a[i], b[i])[1])
        np.testing.assert_allclose(inverse_jacobian(a)[i], inverse_jacobian(a[i]))
    np.testing.assert_allclose(compose(a[0], b)[2], compose(a[0], b[2]))


@given(SEEDS)
@FAST
def test_compose_with_jacobians_is_compose_and_its_jacobians_to_the_bit(seed):
    rng = np.random.default_rng(seed)
    for a, b in [(_poses(rng, 1)[0], _poses(rng, 1)[0]), (_poses(rng, 4), _poses(rng, 1)[0])]:
        composed, j_a, j_b = compose_with_jacobians(a, b)
        np.testing.assert_array_equal(composed, compose(a, b))
        for joint, alone in zip((j_a, j_b), compose_jacobians(a, b), strict=True):
            np.testing.assert_array_equal(joint, alone)


@given(SEEDS)
@FAST
def test_one_pose_gives_its_row_of_a_stack_to_the_bit(seed):
    """The single-pose paths (a float angle, one pose each) written out for speed give what the
    stacked numpy path gives each row, to the last bit, edge angles included."""
    rng = np.random.default_rng(seed)
    a, b = _poses(rng, 8), _poses(rng, 8)
    a[:4, 2] = [np.pi, -np.pi, 0.0, -0.0]
    b[:4, 2] = [np.pi, np.pi, -0.0, 3 * np.pi]
    composed, j_a, j_b = compose_with_jacobians(a, b)
    angles = a[:, 2] + b[:, 2]
    for i in range(len(a)):
        one, one_a, one_b = compose_with_jacobians(a[i], b[i])
        for row, single in ((composed, one), (j_a, one_a), (j_b, one_b)):
            assert row[i].tobytes() == single.tobytes()
        assert rot2(a[:, 2])[i].tobytes() == rot2(float(a[i, 2])).tobytes()
        assert wrap_angle(angles)[i].tobytes() == wrap_angle(float(angles[i])).tobytes()
    assert np.isnan(wrap_angle(float("nan"))) and np.isnan(wrap_angle(float("inf")))


@given(st.floats(allow_nan=True, allow_infinity=True), st.floats(0.0, 1e3))
@FAST
def test_clamp_is_np_clip_to_the_bit(value, bound):
    expected = np.clip(np.float64(value), -bound, bound)
    assert np.float64(clamp(value, bound)).tobytes() == expected.tobytes()
