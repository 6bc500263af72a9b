"""The correlated merge of carried poses (stsf_gym/estimators/carried_poses.py)."""

import numpy as np
import pytest

from stsf_gym.estimators.carried_poses import CarriedPoses
from stsf_gym.fusion import merge_gaussians


def test_one_independent_pose_is_eq_23_24():
    P, R = np.diag([4e-4, 1e-4, 2e-4]), np.diag([1e-4, 3e-4, 1e-4])
    x, z = np.array([1.0, 2.0, 0.1]), np.array([1.02, 1.99, 0.12])
    carried = CarriedPoses()
    carried.add("a", R)
    correction, P_new = carried.merge(P, {"a": np.eye(3)}, z - x, gate=np.inf)
    expected_x, expected_P = merge_gaussians(x, P, z, R, angle_index=[2])
    np.testing.assert_allclose(x + correction, expected_x, atol=1e-12)
    np.testing.assert_allclose(P_new, expected_P, atol=1e-15)


def test_gate_rejects_and_changes_nothing():
    carried = CarriedPoses()
    carried.add("a", np.eye(3) * 1e-4)
    cross = carried.cross.copy()
    assert carried.merge(np.eye(3) * 1e-4, {"a": np.eye(3)}, np.array([1.0, 0, 0]), 11.3) is None
    np.testing.assert_array_equal(carried.cross, cross)


def test_remove_keeps_the_other_blocks():
    carried = CarriedPoses()
    for key, scale in (("a", 1.0), ("b", 2.0), ("c", 3.0)):
        carried.add(key, np.eye(3) * scale)
    carried.predict(np.eye(3), np.eye(3) * 0.5)
    carried.remove(["b", "unknown"])
    assert carried.keys == ["a", "c"]
    np.testing.assert_allclose(np.diag(carried.joint), [1.5] * 3 + [3.5] * 3)
    np.testing.assert_allclose(carried.joint[:3, 3:], np.eye(3) * 0.5)
    with pytest.raises(ValueError, match="exists already"):
        carried.add("a", np.eye(3))


def _sliding_track(rng, samples: int, steps: int, frames: int, correlated: bool):
    """Errors and covariance of an estimate that merges, at each step, the average of the last
    ``frames`` carried poses (each step's odometry noise shared by the estimate and the poses):
    STSF's situation, where every frame is merged again and again."""
    Q, R = np.diag([1e-4, 2e-4, 5e-5]), np.diag([4e-4, 1e-4, 2e-4])
    F = np.array([[1.0, 0.0, -0.05], [0.0, 1.0, 0.1], [0.0, 0.0, 1.0]])
    P = np.diag([1e-3, 1e-3, 1e-3])
    e = rng.multivariate_normal(np.zeros(3), P, samples)
    eps: dict[int, np.ndarray] = {}
    carried = CarriedPoses()
    for step in range(steps):
        du = rng.multivariate_normal(np.zeros(3), Q, samples)
        e = e @ F.T + du
        eps = {k: v @ F.T + du for k, v in eps.items()}
        P = F @ P @ F.T + Q
        carried.predict(F, Q)
        eps[step] = rng.multivariate_normal(np.zeros(3), R, samples)
        carried.add(step, R)
        carried.remove([step - frames])
        eps.pop(step - frames, None)
        weights = {k: np.eye(3) / len(eps) for k in eps}
        innovation = sum(v / len(eps) for v in eps.values()) - e
        if not correlated:  # eq. 23-24 as if the averaged poses were independent
            carried.cross[:] = 0.0
        gains = []
        for basis in np.eye(3):  # the merge is linear: its gain column by column
            trial = CarriedPoses()
            trial.keys, trial.cross, trial.joint = carried.keys, carried.cross, carried.joint
            gains.append(trial.merge(P, weights, basis, gate=np.inf)[0])
        _, P = carried.merge(P, weights, np.zeros(3), gate=np.inf)
        e = e + innovation @ np.array(gains)
    return e, P


def test_merging_a_track_again_and_again_stays_consistent():
    rng = np.random.default_rng(0)
    e, P = _sliding_track(rng, samples=4000, steps=12, frames=4, correlated=True)
    nees = np.einsum("ni,ij,nj->n", e, np.linalg.inv(P), e)
    assert nees.mean() == pytest.approx(3.0, rel=0.08)
    np.testing.assert_allclose(np.cov(e.T), P, rtol=0.15, atol=2e-6)


def test_ignoring_the_correlation_is_over_confident():
    e, P = _sliding_track(np.random.default_rng(0), 4000, 12, 4, correlated=False)
    nees = np.einsum("ni,ij,nj->n", e, np.linalg.inv(P), e)
    assert nees.mean() > 4.5
