"""The camera view test's compiled kernels give the numpy expressions they replaced, to the
bit: boards seen edge-on (where the facing test's sign is rounding noise and only the same
order of additions agrees) and corners on, past and NaN at the frame's edges."""

import numpy as np
import pytest

from stsf_gym.envs.worlds.corridor import _facing_and_near, _inside_frame


@pytest.mark.parametrize("seed", range(10))
def test_facing_and_near_is_einsum_and_norm_even_edge_on(seed):
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(36, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    eye, to_eye = rng.normal(0, 10, 3), rng.normal(0, 10, (36, 3))
    edge_on = rng.random(36) < 0.7  # the way to the eye made perpendicular to the normal
    to_eye[edge_on] -= np.sum(to_eye * normals, axis=1)[edge_on, None] * normals[edge_on]
    centres = eye - to_eye
    far = float(np.median(np.linalg.norm(to_eye, axis=1)))
    facing = np.einsum("ij,ij->i", normals, eye - centres) > 0
    near = np.linalg.norm(centres - eye, axis=1) < far
    np.testing.assert_array_equal(_facing_and_near(normals, centres, eye, far), facing & near)


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
