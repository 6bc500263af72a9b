"""The joint error covariance of the estimators (stsf_gym/estimators/pose_errors.py)."""

import numpy as np
import pytest

from stsf_gym.estimators.odometry_model import (
    OdometryNoise,
    integrate_wheel_travel,
    odometry_step,
)
from stsf_gym.estimators.pose_errors import PoseErrors
from stsf_gym.fusion import merge_gaussians

NO_CALIBRATION = np.zeros((3, 3))


def nees(errors: np.ndarray, cov: np.ndarray) -> float:
    return float(np.einsum("ni,ij,nj->n", errors, np.linalg.inv(cov), errors).mean())


def test_one_independent_pose_is_eq_23_24():
    P, R = np.diag([4e-4, 1e-4, 2e-4]), np.diag([1e-4, 3e-4, 1e-4])
    x, z = np.array([1.0, 2.0, 0.1]), np.array([1.02, 1.99, 0.12])
    errors = PoseErrors(P, NO_CALIBRATION)
    errors.add("a", R, NO_CALIBRATION)
    correction = errors.merge({"a": np.eye(3)}, z - x, gate=np.inf)
    expected_x, expected_P = merge_gaussians(x, P, z, R, angle_index=[2])
    np.testing.assert_allclose(x + correction, expected_x, atol=1e-12)
    np.testing.assert_allclose(errors.P, expected_P, atol=1e-15)


def test_ekf_update_is_the_joseph_form():
    P, R = np.diag([4e-4, 1e-4, 2e-4]), np.diag([1e-4, 3e-5])
    H = np.array([[-0.8, -0.6, 0.0], [0.12, -0.16, -1.0]])
    nu = np.array([0.01, -0.004])
    errors = PoseErrors(P, NO_CALIBRATION)
    correction = errors.correct(H, R, nu, gate=np.inf)
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    A = np.eye(3) - K @ H
    np.testing.assert_allclose(correction, K @ nu, atol=1e-15)
    np.testing.assert_allclose(errors.P, A @ P @ A.T + K @ R @ K.T, atol=1e-15)


def test_gate_rejects_and_changes_nothing():
    errors = PoseErrors(np.eye(3) * 1e-4, NO_CALIBRATION)
    errors.add("a", np.eye(3) * 1e-4, NO_CALIBRATION)
    joint = errors.joint.copy()
    assert errors.merge({"a": np.eye(3)}, np.array([1.0, 0, 0]), 11.3) is None
    assert errors.correct(np.eye(3), np.eye(3), np.array([np.nan, 0, 0]), 11.3) is None
    np.testing.assert_array_equal(errors.joint, joint)


def test_remove_and_restart_keep_the_other_blocks():
    errors = PoseErrors(np.eye(3), np.eye(3) * 2.0)
    for key, scale in (("a", 1.0), ("b", 2.0), ("c", 3.0)):
        errors.add(key, np.eye(3) * scale, np.eye(3))
    errors.remove(["b", "unknown"])
    assert errors.keys == ["a", "c"]
    np.testing.assert_allclose(np.diag(errors.joint)[6:], [3.0] * 3 + [5.0] * 3)
    np.testing.assert_allclose(errors.joint[6:9, 9:12], np.eye(3) * 2.0)  # shared calibration
    with pytest.raises(ValueError, match="exists already"):
        errors.add("a", np.eye(3), NO_CALIBRATION)
    errors.restart(np.eye(3) * 0.5)
    assert errors.keys == [] and errors.joint.shape == (6, 6)
    np.testing.assert_allclose(errors.joint[:3, 3:], 0.0)
    np.testing.assert_allclose(errors.P, np.eye(3) * 0.5)


TRAVELS = [(0.012, 0.0125)] * 300 + [(0.004, 0.02)] * 60 + [(0.0125, 0.012)] * 400


def _drive(samples: int, rng, noise: OdometryNoise, wheelbase: float = 0.3):
    """Dead reckoning's error over 9 m with turns: one radius error per wheel and one wheelbase
    error per run (as the env draws them per episode), slip per step."""
    calibration = rng.normal(size=(samples, 3)) * np.sqrt(np.diag(noise.calibration_cov))
    mean, true = np.zeros(3), np.zeros((samples, 3))
    errors = PoseErrors(np.zeros((3, 3)), noise.calibration_cov)
    checkpoints = []
    for step, d in enumerate(TRAVELS):
        mean, F, G, G_c = odometry_step(mean, *d, wheelbase)
        errors.predict(F, G @ np.diag(noise.slip_variances(*d)) @ G.T, G_c)
        slip = rng.normal(size=(samples, 2)) * np.sqrt(noise.slip_variances(*d))
        rolled = np.array(d) / (1 + calibration[:, :2]) + slip  # believed radius 1 + c too big
        bases = wheelbase / (1 + calibration[:, 2])
        true = np.array(
            [integrate_wheel_travel(p, *w, b) for p, w, b in zip(true, rolled, bases, strict=True)]
        )
        if step % 250 == 249:
            checkpoints.append((mean - true, errors.P))
    return checkpoints


@pytest.mark.slow
def test_dead_reckoning_with_fixed_calibration_errors_is_consistent():
    """First order: exact while the heading error stays small. With the env's calibration
    errors that holds for the first 3 m; after 9 m and a turn the heading is about 0.15 rad off
    and the position's second-order error (d theta^2 / 2) leaves the thin ellipsoid the fixed
    errors span, so errors ten times smaller are checked over the whole drive."""
    env_sized = OdometryNoise(2e-6, radius_var=0.0033**2, wheelbase_var=0.01**2)
    error, P = _drive(3000, np.random.default_rng(0), env_sized)[0]
    assert nees(error, P) == pytest.approx(3.0, rel=0.1)
    smaller = OdometryNoise(2e-6, radius_var=0.00033**2, wheelbase_var=0.001**2)
    for error, P in _drive(3000, np.random.default_rng(1), smaller):
        assert nees(error, P) == pytest.approx(3.0, rel=0.1)


def test_merging_a_track_again_and_again_stays_consistent():
    """STSF's situation: at each step the average of the last four carried poses is merged;
    every frame is merged again and again, the odometry noise is shared, and each pose's error
    depends on the calibration too."""
    rng, samples = np.random.default_rng(0), 4000
    Q, R = np.diag([1e-4, 2e-4, 5e-5]), np.diag([4e-4, 1e-4, 2e-4])
    F = np.array([[1.0, 0.0, -0.05], [0.0, 1.0, 0.1], [0.0, 0.0, 1.0]])
    G_c = np.array([[0.1, 0.1, 0.0], [0.0, 0.0, 0.05], [-0.3, 0.3, 0.02]])
    M = np.array([[0.5, 0.5, 0.0], [0.1, -0.1, 0.0], [0.0, 0.0, 0.0]])
    sigma_c = np.diag([0.02, 0.02, 0.03]) ** 2
    c = rng.normal(size=(samples, 3)) * np.sqrt(np.diag(sigma_c))
    errors = PoseErrors(np.diag([1e-3, 1e-3, 1e-3]), sigma_c)
    e = rng.multivariate_normal(np.zeros(3), errors.P, samples)
    eps: dict[int, np.ndarray] = {}
    for step in range(12):
        du = rng.multivariate_normal(np.zeros(3), Q, samples) + c @ G_c.T
        e = e @ F.T + du
        eps = {k: v @ F.T + du for k, v in eps.items()}
        errors.predict(F, Q, G_c)
        eps[step] = rng.multivariate_normal(np.zeros(3), R, samples) + c @ M.T
        errors.add(step, R, M)
        errors.remove([step - 4])
        eps.pop(step - 4, None)
        weights = {k: np.eye(3) / len(eps) for k in eps}
        innovation = sum(v / len(eps) for v in eps.values()) - e
        gains = []
        for basis in np.eye(3):  # the update is linear: its gain column by column
            trial = PoseErrors(np.eye(3), sigma_c)
            trial.keys, trial.joint = list(errors.keys), errors.joint
            gains.append(trial.merge(weights, basis, gate=np.inf))
        errors.merge(weights, np.zeros(3), gate=np.inf)
        e = e + innovation @ np.array(gains)
    assert nees(e, errors.P) == pytest.approx(3.0, rel=0.08)
    sampling_std = np.sqrt(np.outer(np.diag(errors.P), np.diag(errors.P)) / samples)
    assert np.all(np.abs(np.cov(e.T) - errors.P) < 4 * sampling_std)


def test_prediction_moves_the_estimate_and_every_carried_pose_alike():
    """``e <- F e + G_c c + G w`` and the same for each ``eps_j``: the joint prediction is
    ``T Y T^T + B Q B^T`` with ``F`` and ``G_c`` in the rows of every pose, to the bit."""
    rng = np.random.default_rng(4)
    considered = np.diag(rng.uniform(1e-4, 1e-3, 5))
    errors = PoseErrors(np.diag([4e-4, 1e-4, 2e-4]), considered)
    for key in range(4):
        errors.add(key, np.diag(rng.uniform(1e-4, 1e-3, 3)), rng.normal(size=(3, 3)))
    F, Q = np.eye(3) + rng.normal(size=(3, 3)) / 10, np.diag([1e-5, 2e-5, 1e-6])
    G_c = rng.normal(size=(3, 3))
    size = len(errors.joint)
    T, B = np.eye(size), np.zeros((size, 3))
    for start in [0, *range(3 + len(considered), size, 3)]:
        T[start : start + 3, start : start + 3] = F
        T[start : start + 3, 3:6] = G_c  # the first three considered: the wheel calibration
        B[start : start + 3] = np.eye(3)
    joint = T @ errors.joint @ T.T + B @ Q @ B.T
    errors.predict(F, Q, G_c)
    np.testing.assert_array_equal(errors.joint, 0.5 * (joint + joint.T))
