"""Eq. 2-5: STSF over landmark tracks, its joint covariance, weights and consistency."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stsf_gym.fusion import (
    STSFTrack,
    significance,
    stsf_fuse,
    transform_pose_track,
    transform_range_track,
)
from stsf_gym.fusion.covariance import DenseCovariance
from stsf_gym.geometry import compose, compose_jacobians, inverse, wrap_angle

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=25, deadline=None)
C_MEAS = np.diag([0.04, 0.06, 0.02]) ** 2
Q_ODOM = np.diag([0.02, 0.02, 0.01]) ** 2


def _random_track(rng: np.random.Generator, k: int):
    zs = np.column_stack([rng.uniform(-5, 5, (k, 2)), rng.uniform(-np.pi, np.pi, k)])
    us = np.column_stack([rng.uniform(-1, 1, (k - 1, 2)), rng.uniform(-0.5, 0.5, k - 1)])
    a, b = rng.normal(size=(2, k, 3, 3)) * 0.1
    return zs, a @ np.swapaxes(a, 1, 2) + 1e-4 * np.eye(3), us, b[1:] @ np.swapaxes(b[1:], 1, 2)


def _simulate(rng, k, landmark, step, noisy_odometry=True):
    """Measured track of a static landmark from a moving robot, and the true TS(k)."""
    pose, zs, us = np.zeros(3), [], []
    for j in range(k):
        zs.append(compose(inverse(pose), landmark) + rng.multivariate_normal(np.zeros(3), C_MEAS))
        if j < k - 1:
            noise = rng.multivariate_normal(np.zeros(3), Q_ODOM) if noisy_odometry else 0.0
            us.append(step + noise)
            pose = compose(pose, step)
    covs, qs = np.repeat(C_MEAS[None], k, 0), np.repeat(Q_ODOM[None], k - 1, 0)
    return np.array(zs), covs, np.array(us).reshape(-1, 3), qs, compose(inverse(pose), landmark)


def test_noise_free_sets_all_land_on_the_current_measurement():
    landmark, step = np.array([6.0, 2.0, 2.5]), np.array([0.3, 0.02, 0.08])
    half = step / 2  # two odometry increments per frame: half (+) rest = step
    rest = compose(inverse(half), step)
    track, pose = STSFTrack(), np.zeros(3)
    for _ in range(12):
        track.add(compose(inverse(pose), landmark), C_MEAS)
        track.move(half, Q_ODOM / 2)
        track.move(rest, Q_ODOM / 2)
        pose = compose(pose, step)
    ts, _ = track.transformed()
    np.testing.assert_allclose(ts, np.repeat(ts[-1:], 12, 0), atol=1e-12)
    for method in ("significance", "gls"):
        np.testing.assert_allclose(track.fuse(method).x, ts[-1], atol=1e-12)


@pytest.mark.parametrize("method", ["significance", "gls"])
def test_one_measurement_set_is_the_conventional_result(method):
    track = STSFTrack()
    track.move([1.0, 0.0, 0.1], Q_ODOM)  # motion before the first frame is irrelevant
    track.add([2.0, 1.0, 0.3], C_MEAS)
    result = track.fuse(method)
    np.testing.assert_allclose(result.x, [2.0, 1.0, 0.3])
    np.testing.assert_allclose(result.cov, C_MEAS)
    np.testing.assert_allclose(result.weights, np.eye(3)[None])


@given(SEEDS, st.integers(1, 6))
@FAST
def test_joint_covariance_matches_finite_differences(seed, k):
    zs, covs, us, qs = _random_track(np.random.default_rng(seed), k)
    _, joint = transform_pose_track(zs, covs, us, qs)
    params = np.concatenate([zs.ravel(), us.ravel()])

    def ts_of(p):
        return transform_pose_track(p[: 3 * k].reshape(k, 3), covs, p[3 * k :], qs)[0]

    columns = []
    for i in range(params.size):
        step = np.zeros_like(params)
        step[i] = 1e-6
        diff = ts_of(params + step) - ts_of(params - step)
        diff[:, 2] = wrap_angle(diff[:, 2])
        columns.append(diff.ravel() / 2e-6)
    jac = np.column_stack(columns)
    inputs = np.zeros((params.size, params.size))
    for i, c in enumerate([*covs, *qs]):
        inputs[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = c
    np.testing.assert_allclose(joint.dense(), jac @ inputs @ jac.T, atol=1e-7)


@given(SEEDS, st.integers(1, 6))
@FAST
def test_factored_covariance_agrees_with_its_dense_matrix(seed, k):
    rng = np.random.default_rng(seed)
    ts, joint = transform_pose_track(*_random_track(rng, k))
    dense = DenseCovariance(joint.dense(), k, 3)
    weights = rng.normal(size=(k, 2, 3))
    np.testing.assert_allclose(joint.transform(weights), dense.transform(weights), atol=1e-10)
    np.testing.assert_allclose(joint.marginals(), dense.marginals(), atol=1e-12)
    for method in ("significance", "gls"):
        a = stsf_fuse(ts, joint, method, angle_index=[2])
        b = stsf_fuse(ts, joint.dense(), method, angle_index=[2])
        np.testing.assert_allclose(a.x, b.x, atol=1e-10)
        np.testing.assert_allclose(a.cov, b.cov, atol=1e-10)


def test_gls_is_the_best_linear_unbiased_estimate():
    rng = np.random.default_rng(5)
    ts, joint = transform_pose_track(
        *_simulate(rng, 8, np.array([5.0, 1.0, 0.2]), np.array([0.3, 0.0, 0.05]))[:4]
    )
    gls, sig = stsf_fuse(ts, joint, "gls", [2]), stsf_fuse(ts, joint, "significance", [2])
    ident = np.tile(np.eye(3), (8, 1))
    np.testing.assert_allclose(
        gls.cov, np.linalg.inv(ident.T @ np.linalg.solve(joint.dense(), ident)), rtol=1e-8
    )
    np.testing.assert_allclose(gls.weights.sum(axis=0), np.eye(3), atol=1e-10)
    assert np.linalg.eigvalsh(sig.cov - gls.cov).min() > -1e-12
    assert np.trace(gls.cov) < np.trace(C_MEAS)  # better than the current frame alone


def test_significance_is_a_distribution_that_rejects_an_outlier():
    rng = np.random.default_rng(9)
    truth = np.array([3.0, 1.0, 0.4])
    zs = truth + rng.multivariate_normal(np.zeros(3), C_MEAS, size=10)
    zs[4] += [0.8, 0.0, 0.0]  # 20 sigma off
    ts, joint = transform_pose_track(
        zs, np.repeat(C_MEAS[None], 10, 0), np.zeros((9, 3)), np.zeros((9, 3, 3))
    )
    for gate in (None, 0.0):
        p = significance(ts, joint, angle_index=[2], gate=gate)
        assert (p >= 0).all() and p.sum() == pytest.approx(1.0)
        assert p[4] < 1e-6 * p.max()
    fused = stsf_fuse(ts, joint, angle_index=[2]).x
    assert np.abs(fused - truth)[0] < 0.06
    plain_mean = zs.mean(axis=0)
    assert np.abs(fused - truth)[0] < np.abs(plain_mean - truth)[0]


@pytest.mark.parametrize("method", ["significance", "gls"])
def test_error_shrinks_like_one_over_sqrt_n(method):
    rng = np.random.default_rng(21)
    truth = np.array([3.0, 1.0, 0.4])
    rms = {}
    for n in (1, 16):
        errors = []
        for _ in range(300):
            zs, covs, us, qs, _ = _simulate(rng, n, truth, np.zeros(3), noisy_odometry=False)
            ts, joint = transform_pose_track(zs, covs, us, np.zeros_like(qs))
            errors.append(stsf_fuse(ts, joint, method, angle_index=[2]).x - truth)
        rms[n] = np.sqrt(np.mean(np.sum(np.square(errors), axis=1)))
    assert 3.2 < rms[1] / rms[16] < 5.0


@pytest.mark.parametrize("method", ["significance", "gls"])
def test_fused_covariance_is_consistent_with_odometry_noise(method):
    rng = np.random.default_rng(33)
    landmark, step = np.array([6.0, 1.5, np.pi - 0.05]), np.array([0.3, 0.0, 0.03])
    nees, nees_independent = [], []
    for _ in range(300):
        zs, covs, us, qs, truth = _simulate(rng, 8, landmark, step)
        ts, joint = transform_pose_track(zs, covs, us, qs)
        # what a filter that forgets the shared odometry errors would claim
        independent = np.kron(np.eye(8), np.ones((3, 3))) * joint.dense()
        for sigma, out in ((joint, nees), (independent, nees_independent)):
            result = stsf_fuse(ts, sigma, method, angle_index=[2])
            error = result.x - truth
            error[2] = wrap_angle(error[2])
            out.append(error @ np.linalg.solve(result.cov, error))
    assert 2.5 < np.mean(nees) < 3.5  # chi-square with 3 degrees of freedom
    assert np.mean(nees_independent) > 5.0  # over-confident: the test can tell


def test_angles_are_fused_across_pi():
    ts = np.array([[1.0, 0.0, np.pi - 0.02], [1.0, 0.0, -np.pi + 0.02]])
    joint = np.kron(np.eye(2), C_MEAS)
    for method in ("significance", "gls"):
        assert abs(stsf_fuse(ts, joint, method, angle_index=[2]).x[2]) == pytest.approx(np.pi)


def test_max_frames_keeps_the_latest_frames():
    rng = np.random.default_rng(4)
    zs, covs, us, qs, _ = _simulate(rng, 9, np.array([5.0, 1.0, 0.2]), np.array([0.3, 0, 0.05]))
    short = STSFTrack(max_frames=4)
    for j in range(9):
        if j:
            short.move(us[j - 1], qs[j - 1])
        short.add(zs[j], covs[j])
    assert len(short) == 4
    expected = stsf_fuse(*transform_pose_track(zs[5:], covs[5:], us[5:], qs[5:]), angle_index=[2])
    np.testing.assert_allclose(short.fuse().x, expected.x)
    np.testing.assert_allclose(short.fuse().cov, expected.cov)


def test_moves_accumulate_with_their_covariance():
    u1, u2 = np.array([0.3, 0.1, 0.2]), np.array([0.2, -0.1, -0.4])
    track = STSFTrack()
    track.add([4.0, 1.0, 0.0], C_MEAS)
    track.move(u1, Q_ODOM)
    track.move(u2, 2 * Q_ODOM)
    track.add([3.5, 0.8, 0.1], C_MEAS)
    j1, j2 = compose_jacobians(u1, u2)
    q = j1 @ Q_ODOM @ j1.T + j2 @ (2 * Q_ODOM) @ j2.T
    ts, joint = transform_pose_track(
        [[4.0, 1.0, 0.0], [3.5, 0.8, 0.1]], [C_MEAS] * 2, [compose(u1, u2)], [q]
    )
    np.testing.assert_allclose(track.transformed()[0], ts)
    np.testing.assert_allclose(track.transformed()[1].dense(), joint.dense())


def test_range_track_carries_ranges_and_correlates_them():
    ts, joint = transform_range_track(
        [5.0, 4.6, 4.1], [0.01, 0.02, 0.03], [-0.4, -0.5], [0.001, 0.002]
    )
    np.testing.assert_allclose(ts[:, 0], [4.1, 4.1, 4.1])
    expected = np.diag([0.01, 0.02, 0.03]) + np.array(
        [[0.003, 0.002, 0.0], [0.002, 0.002, 0.0], [0.0, 0.0, 0.0]]
    )
    np.testing.assert_allclose(joint.dense(), expected, atol=1e-15)
    result = stsf_fuse(ts, joint, "gls")
    assert result.x[0] == pytest.approx(4.1)
    assert result.cov[0, 0] < 0.03


def test_invalid_input_is_rejected():
    with pytest.raises(ValueError, match="empty"):
        STSFTrack().fuse()
    with pytest.raises(ValueError, match="max_frames"):
        STSFTrack(max_frames=0)
    with pytest.raises(ValueError, match="method"):
        stsf_fuse(np.zeros((2, 1)), np.eye(2), method="mean")
    with pytest.raises(ValueError, match="sigma"):
        stsf_fuse(np.zeros((2, 3)), np.eye(3))
    with pytest.raises(ValueError, match="us"):
        transform_pose_track(np.zeros((3, 3)), np.zeros((3, 3, 3)), np.zeros((1, 3)), [])
