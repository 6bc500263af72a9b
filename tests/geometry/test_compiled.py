"""The compiled kernels give the numpy code they replaced, to the bit."""

import numpy as np
import pytest

from stsf_gym.camera_model import distort, undistort


def numpy_undistort(xy_d: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """The fixed-point iteration as numpy wrote it before it was compiled: all points at once,
    stopping when every point returned itself to the bit."""
    k1, k2, p1, p2, k3 = dist
    xy = np.array(xy_d, dtype=float)
    x_d, y_d = xy[..., 0].copy(), xy[..., 1].copy()
    x, y = xy[..., 0], xy[..., 1]
    for _ in range(20):
        r2 = x * x + y * y
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        x_new, y_new = (x_d - dx) / radial, (y_d - dy) / radial
        if x_new.tobytes() == x.tobytes() and y_new.tobytes() == y.tobytes():
            break
        x[...], y[...] = x_new, y_new
    return xy


def numpy_distort(xy: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """The lens model as numpy wrote it before it was compiled."""
    k1, k2, p1, p2, k3 = dist
    x, y = xy[..., 0], xy[..., 1]
    r2 = x * x + y * y
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.stack([xd, yd], axis=-1)


@pytest.mark.parametrize(
    ("compiled", "reference", "reach"),
    [(distort, numpy_distort, 0.8), (undistort, numpy_undistort, 0.6)],
    ids=["distort", "undistort"],
)
def test_the_lens_model_is_the_numpy_code_to_the_bit(compiled, reference, reach):
    rng = np.random.default_rng(7)
    for _ in range(200):
        dist = rng.normal(0.0, [0.2, 0.1, 0.005, 0.005, 0.02])
        points = rng.uniform(-reach, reach, (int(rng.integers(1, 40)), 2))
        assert compiled(points, dist).tobytes() == reference(points, dist).tobytes()
    grid = rng.uniform(-0.5, 0.5, (3, 5, 2))  # any leading shape
    assert compiled(grid, dist).tobytes() == reference(grid, dist).tobytes()
