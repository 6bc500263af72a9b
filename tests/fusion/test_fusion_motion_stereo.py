"""Eq. 8-20: range from two frames of one camera, its variance and the stereo bound."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from stsf_gym.fusion import (
    DegenerateGeometryError,
    motion_stereo_range,
    motion_stereo_variance,
    stereo_range_bound,
)
from stsf_gym.fusion.motion_stereo import motion_stereo_ranges

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)


def _project(points: np.ndarray, f: float) -> np.ndarray:
    return np.column_stack([f * points[:, :2] / points[:, 2:], np.full(len(points), f)])


def _scene(rng: np.random.Generator, n_points: int):
    """Random camera motion and points on a random plane facing camera k, noise-free."""
    f = rng.uniform(300.0, 1000.0)
    while True:
        centre = np.array([*rng.uniform(-1.0, 1.0, 2), rng.uniform(2.0, 10.0)])
        normal = rng.normal(size=3)
        normal /= np.linalg.norm(normal)
        if normal @ centre < 0.3 * np.linalg.norm(centre):
            continue
        basis = np.linalg.svd(normal[None])[2][1:]  # two unit vectors in the plane
        points = centre + rng.uniform(-0.5, 0.5, (n_points, 2)) @ basis
        R = Rotation.from_rotvec(rng.normal(size=3) * 0.15).as_matrix()
        t = rng.normal(size=3)
        t *= rng.uniform(0.2, 1.0) / np.linalg.norm(t)
        prev = points @ R.T + t
        ray_angle = np.linalg.norm(np.cross(prev, points @ R.T), axis=1) / (
            np.linalg.norm(prev, axis=1) * np.linalg.norm(points, axis=1)
        )
        if points[:, 2].min() > 0.5 and prev[:, 2].min() > 0.5 and ray_angle.min() > 1e-2:
            return _project(prev, f), _project(points, f), R, t, normal, float(normal @ centre)


@given(SEEDS)
@FAST
def test_noise_free_single_point_is_exact(seed):
    q_prev, q_curr, R, t, n, D = _scene(np.random.default_rng(seed), 1)
    assert motion_stereo_range(q_prev[0], q_curr[0], R, t, n) == pytest.approx(D, rel=1e-9)


@given(SEEDS, st.integers(2, 8))
@FAST
def test_noise_free_points_on_a_plane_are_exact(seed, n_points):
    q_prev, q_curr, R, t, n, D = _scene(np.random.default_rng(seed), n_points)
    assert motion_stereo_range(q_prev, q_curr, R, t, n) == pytest.approx(D, rel=1e-9)


def test_single_point_matches_eq_20():
    q_prev, q_curr, R, t, n, _ = _scene(np.random.default_rng(0), 1)
    (u1, v1, f1), q = q_prev[0], q_curr[0]
    r = R @ q
    a, b = f1 * r[0] - u1 * r[2], f1 * r[1] - v1 * r[2]
    c, d = -(n @ q) * (f1 * t[0] - u1 * t[2]), -(n @ q) * (f1 * t[1] - v1 * t[2])
    expected = (a * c + b * d) / (a**2 + b**2)
    assert motion_stereo_range(q_prev[0], q, R, t, n) == pytest.approx(expected, rel=1e-12)


@given(SEEDS, st.integers(1, 4))
@FAST
def test_degenerate_geometry_raises(seed, n_points):
    rng = np.random.default_rng(seed)
    q_prev, q_curr, R, t, n, D = _scene(rng, n_points)
    with pytest.raises(DegenerateGeometryError, match="baseline"):
        motion_stereo_range(q_prev, q_curr, R, np.zeros(3), n)
    # camera moved along the line of sight of the first point: no parallax there
    point = D / (n @ q_curr[0]) * q_curr[0]
    t_along = rng.uniform(0.1, 0.9) * (R @ point)
    prev = _project((R @ point + t_along)[None], q_curr[0, 2])
    with pytest.raises(DegenerateGeometryError, match="parallel"):
        motion_stereo_range(prev[0], q_curr[0], R, t_along, n)
    # tiny baseline: the rays are parallel to within rounding
    prev = _project((R @ point + 1e-12 * t)[None], q_curr[0, 2])
    with pytest.raises(DegenerateGeometryError):
        motion_stereo_range(prev[0], q_curr[0], R, 1e-12 * t, n)


@given(SEEDS, st.integers(1, 6))
@FAST
def test_ranges_under_several_motions_equal_one_solve_each(seed, n_points):
    """The finite-difference helper's ranges are motion_stereo_range's to the bit, the rotation
    repeated or not, with None where one motion is degenerate."""
    rng = np.random.default_rng(seed)
    q_prev, q_curr, R, t, n, _ = _scene(rng, n_points)
    shift = np.eye(3) * 1e-6
    turned = Rotation.from_rotvec(shift[1]).as_matrix() @ R
    motions = [(R, t), (R, t + shift[0]), (R, t + shift[1]), (turned, t), (R, np.zeros(3))]
    expected = []
    for motion in motions:
        try:
            expected.append(motion_stereo_range(q_prev, q_curr, *motion, n))
        except DegenerateGeometryError:
            expected.append(None)
    assert expected[-1] is None and None not in expected[:-1]
    assert motion_stereo_ranges(q_prev, q_curr, motions, n) == expected


def test_ray_parallel_to_plane_and_bad_inputs_raise():
    q = np.array([10.0, 0.0, 500.0])
    with pytest.raises(DegenerateGeometryError, match="plane"):
        motion_stereo_range(q, q, np.eye(3), np.array([0.1, 0, 0]), np.array([0.0, 1.0, 0.0]))
    args = (np.eye(3), np.array([0.1, 0, 0]), np.array([0.0, 0.0, 1.0]))
    for q_prev, q_curr in ((q[:2], q[:2]), (q, np.stack([q, q])), (np.zeros((2, 2, 3)),) * 2):
        with pytest.raises(ValueError, match="shape"):
            motion_stereo_range(q_prev, q_curr, *args)
    with pytest.raises(ValueError, match="unit"):
        motion_stereo_range(q, q, np.eye(3), args[1], np.array([0.0, 0.0, 2.0]))
    with pytest.raises(ValueError, match="rotation"):
        motion_stereo_range(q, q, 2 * np.eye(3), *args[1:])
    with pytest.raises(ValueError, match="finite"):
        motion_stereo_range(q * np.nan, q, *args)
    assert issubclass(DegenerateGeometryError, ValueError)


def _monte_carlo_variance(scene, sigma_px, cov_t, cov_rot, rng, samples=2000):
    q_prev, q_curr, R, t, n, _ = scene
    ranges = []
    for _ in range(samples):
        noise = rng.normal(scale=sigma_px, size=(2, *q_prev.shape))
        noise[..., 2] = 0.0
        R_err = R @ Rotation.from_rotvec(rng.multivariate_normal(np.zeros(3), cov_rot)).as_matrix()
        t_err = t + rng.multivariate_normal(np.zeros(3), cov_t)
        ranges.append(motion_stereo_range(q_prev + noise[0], q_curr + noise[1], R_err, t_err, n))
    return np.var(ranges)


@pytest.mark.slow
@pytest.mark.parametrize(("seed", "n_points"), [(11, 1), (12, 4)])
def test_variance_matches_monte_carlo(seed, n_points):
    rng = np.random.default_rng(seed)
    scene = _scene(rng, n_points)
    sigma_px, cov_t, cov_rot = 0.5, np.diag([0.01, 0.005, 0.01]) ** 2, np.diag([2e-3] * 3) ** 2
    for use_odometry in (False, True):
        extra = (cov_t, cov_rot) if use_odometry else (np.zeros((3, 3)),) * 2
        predicted = motion_stereo_variance(*scene[:5], sigma_px, *extra)
        simulated = _monte_carlo_variance(scene, sigma_px, *extra, rng)
        assert predicted == pytest.approx(simulated, rel=0.15)
    pixels_only = motion_stereo_variance(*scene[:5], sigma_px)
    assert motion_stereo_variance(*scene[:5], sigma_px, cov_t, cov_rot) > pixels_only


def test_lateral_stereo_variance_equals_the_bound():
    f, b, Z = 500.0, 0.3, 6.0
    point = np.array([[0.0, 0.2, Z]])
    t = np.array([b, 0.0, 0.0])  # camera k-1 sits b to the left of camera k
    q_prev, q_curr = _project(point + t, f), _project(point, f)
    n = np.array([0.0, 0.0, 1.0])
    assert motion_stereo_range(q_prev, q_curr, np.eye(3), t, n) == pytest.approx(Z)
    std = np.sqrt(motion_stereo_variance(q_prev, q_curr, np.eye(3), t, n, 0.5))
    assert std == pytest.approx(stereo_range_bound(Z, f, b, 0.5), rel=1e-9)
    assert stereo_range_bound(Z, f, b, 0.5) == pytest.approx(np.sqrt(2) * 36 * 0.5 / 150)
    np.testing.assert_allclose(stereo_range_bound(np.array([1.0, 2.0]), f, b, 0.5).shape, (2,))
    with pytest.raises(ValueError):
        stereo_range_bound(Z, f, 0.0, 0.5)
