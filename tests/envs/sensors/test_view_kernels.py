"""The camera view test's compiled kernels give the numpy expressions they replaced, to the
bit: distances at the range limit, and corners on, past and NaN at the frame's edges."""

import numpy as np
import pytest

from stsf_gym.envs.worlds.corridor import _facing_and_near, _inside_frame


@pytest.mark.parametrize("seed", range(10))
def test_facing_and_near_is_the_dots_sign_and_the_norm(seed):
    rng = np.random.default_rng(seed)
    dots, eye, centres = rng.normal(size=36), rng.normal(0, 10, 3), rng.normal(0, 10, (36, 3))
    dots[:3] = (0.0, -0.0, np.nan)
    distances = np.linalg.norm(centres - eye, axis=1)
    far = float(distances[5])  # one board exactly at the limit: not near
    expected = (dots > 0) & (distances < far)
    np.testing.assert_array_equal(_facing_and_near(dots, centres, eye, far), expected)


@pytest.mark.parametrize("seed", range(10))
def test_inside_frame_is_the_corner_comparisons(seed):
    rng = np.random.default_rng(seed)
    uv = rng.uniform(-5.0, 330.0, (20, 4, 2))
    uv[:10] = rng.uniform(-0.5, 239.5, (10, 4, 2))  # these inside, but for a NaN
    uv[rng.random((20, 4, 2)) < 0.05] = np.nan
    uv[0, 0] = (-0.5, 239.5)  # on the edges: inside
    right, bottom = 319.5, 239.5
    expected = np.all((uv >= -0.5) & (uv <= (right, bottom)), axis=(1, 2))
    np.testing.assert_array_equal(_inside_frame(uv, right, bottom), expected)
    assert expected.any() and not expected.all()
