"""The landmark range/bearing EKF: accuracy, consistency (NEES), gating and robustness."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.stats import chi2

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.agents.follower import PathFollower
from stsf_gym.estimators import make_estimator
from stsf_gym.estimators.ekf import EKFEstimator
from stsf_gym.estimators.landmark_observation import LandmarkObservation
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import PoseEstimateWrapper, sensor_model

RUN_SEED = 3  # an episode whose calibration errors make dead reckoning drift ~0.85 m in 7 m
RUN_STEPS = 600  # ~7.3 m at 12.2 cm/s, ~60 s simulated, 300 camera frames


def pose_error(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    error = np.asarray(estimate, dtype=float) - truth
    error[2] = math.remainder(error[2], math.tau)
    return error


def assert_spd(cov: np.ndarray) -> None:
    np.testing.assert_allclose(cov, cov.T, rtol=0, atol=1e-15)
    assert np.linalg.eigvalsh(cov).min() > 0


@pytest.fixture(scope="module")
def straight_run():
    """The EKF through the wrapper along Straight10m, the follower driving on the true pose.

    The odometry estimator is fed the same observations: as the follower drives on the true
    pose the trajectory does not depend on the estimate, so this is the odometry estimator's
    run on the same seed, at half the simulation cost. The ideal camera: these tests check the
    filter's mechanics; on this seed's extreme wheel calibration (about 3 sigma) the paper's
    camera, which finds the first wall board later, lets dead reckoning drift past its
    first-order covariance and the filter re-localises (the figures measure that camera).
    """
    env = PoseEstimateWrapper(gym.make("stsf_gym/Straight10m-v0", camera__profile="ideal"), "ekf")
    try:
        obs, info = env.reset(seed=RUN_SEED)
        ekf = env.estimator
        odometry = make_estimator("odometry")
        odometry.reset(ekf.model, ekf.mean, ekf.cov)
        follower = PathFollower.for_env(env)
        nees, frames, min_eig, max_asym = [], 0, np.inf, 0.0
        for _ in range(RUN_STEPS):
            obs, _, terminated, truncated, info = env.step(follower.act(info["true_pose"]))
            odometry.update(obs, env.unwrapped.dt)
            frames += int(obs["image_new"])
            cov = obs["pose_cov"].astype(float).reshape(3, 3)
            np.testing.assert_allclose(cov, ekf.cov, rtol=1e-6, atol=1e-12)  # float32 copy
            error = pose_error(ekf.mean, info["true_pose"])
            nees.append(float(error @ np.linalg.solve(ekf.cov, error)))
            min_eig = min(min_eig, np.linalg.eigvalsh(ekf.cov).min())
            max_asym = max(max_asym, np.abs(ekf.cov - ekf.cov.T).max())
            assert not (terminated or truncated)
        return {
            "truth": info["true_pose"].copy(),
            "ekf_mean": ekf.mean.copy(),
            "ekf_cov": ekf.cov.copy(),
            "odometry_mean": odometry.mean.copy(),
            "nees": np.array(nees),
            "frames": frames,
            "counters": dict(ekf.counters),
            "timings": dict(ekf.timings),
            "min_eig": min_eig,
            "max_asym": max_asym,
        }
    finally:
        env.close()


def test_ekf_beats_dead_reckoning(straight_run):
    truth = straight_run["truth"]
    assert truth[0] > 6.5  # it drove about 7 m
    ekf_error = np.linalg.norm(straight_run["ekf_mean"][:2] - truth[:2])
    odometry_error = np.linalg.norm(straight_run["odometry_mean"][:2] - truth[:2])
    print(f"final position error: ekf {ekf_error:.4f} m, odometry {odometry_error:.4f} m")
    assert odometry_error > 0.15  # the seed is a hard one for dead reckoning (0.21 m)
    assert ekf_error < 0.05
    assert ekf_error < 0.1 * odometry_error
    assert abs(pose_error(straight_run["ekf_mean"], truth)[2]) < 0.01


def test_ekf_is_not_wildly_overconfident(straight_run):
    """One run is one sample of the Monte-Carlo NEES test
    (tests/estimators/test_landmark_estimators.py runs that over ten seeds): its steps are
    correlated, so only gross failures show here."""
    nees = straight_run["nees"]
    print(f"average NEES {nees.mean():.3f}, max {nees.max():.2f}")
    assert 0.3 < nees.mean() < 9.0
    assert nees.max() < chi2.ppf(0.9999, 3) * 2


def test_ekf_counts_updates_and_times_stages(straight_run):
    counters = straight_run["counters"]
    assert counters["frames"] == straight_run["frames"] > 250
    assert counters["landmark_updates"] > 200
    assert counters.get("gated_out", 0) < 0.05 * counters["landmark_updates"]
    assert counters["detections"] == (
        counters["landmark_updates"]
        + counters.get("gated_out", 0)
        + counters.get("out_of_range", 0)
        + counters.get("unusable", 0)
    )
    assert {"odometry", "detect", "update"} <= set(straight_run["timings"])


def test_ekf_covariance_stays_symmetric_positive_definite(straight_run):
    assert straight_run["min_eig"] > 0
    assert straight_run["max_asym"] < 1e-15
    assert_spd(straight_run["ekf_cov"])


# Synthetic measurements: no camera needed.


@pytest.fixture(scope="module")
def model():
    env = gym.make("stsf_gym/Straight10m-v0", camera__enabled=False)
    try:
        env.reset(seed=0)
        return sensor_model(env)
    finally:
        env.close()


def synthetic_observation(model, landmark_id, pose, range_offset=0.0, bearing_offset=0.0):
    """The board of ``landmark_id`` as seen from ``pose``, with offsets, std 1 cm in u and v."""
    landmark = model.landmarks[landmark_id]
    dx, dy = landmark.centre[:2] - pose[:2]
    r = math.hypot(dx, dy) + range_offset
    b = math.atan2(dy, dx) - pose[2] + bearing_offset
    phi = math.atan2(landmark.normal[1], landmark.normal[0]) - pose[2]
    return LandmarkObservation.given(
        landmark,
        np.arange(4),
        np.zeros((4, 2)),
        np.eye(4),
        np.array([r * math.cos(b), r * math.sin(b), phi]),
        np.diag([1e-4, 1e-4, 1e-4]),
    )


def make_ekf(model, pose, std=(0.05, 0.05, 0.02), **options) -> EKFEstimator:
    ekf = make_estimator("ekf", **options)
    ekf.reset(model, pose, np.diag(np.square(std)))
    return ekf


def test_gate_rejects_wrong_measurement_and_leaves_state(model):
    pose = np.array([5.0, 0.1, 0.05])
    ekf = make_ekf(model, pose)
    mean, cov = ekf.mean.copy(), ekf.cov.copy()
    assert not ekf.correct(synthetic_observation(model, 4, pose, range_offset=2.0))
    assert not ekf.correct(synthetic_observation(model, 4, pose, bearing_offset=0.5))
    np.testing.assert_array_equal(ekf.mean, mean)
    np.testing.assert_array_equal(ekf.cov, cov)
    assert ekf.counters["gated_out"] == 2 and ekf.counters["landmark_updates"] == 0


def test_consistent_measurement_is_accepted_and_shrinks_covariance(model):
    truth = np.array([5.0, 0.1, 0.05])
    ekf = make_ekf(model, truth + np.array([0.04, -0.03, 0.01]))
    trace = np.trace(ekf.cov)
    for landmark_id in (4, 2, 3):
        assert ekf.correct(synthetic_observation(model, landmark_id, truth))
        assert np.trace(ekf.cov) < trace
        trace = np.trace(ekf.cov)
        assert_spd(ekf.cov)
    assert ekf.counters["landmark_updates"] == 3 and ekf.counters.get("gated_out", 0) == 0
    # three landmarks fix the pose: the error shrinks to about the measurement noise
    assert np.linalg.norm(pose_error(ekf.mean, truth)[:2]) < 0.02
    assert abs(pose_error(ekf.mean, truth)[2]) < 0.005


def test_gate_threshold_is_the_chi_square_quantile(model):
    pose = np.array([5.0, 0.0, 0.0])
    for probability in (0.9, 0.99):
        ekf = make_ekf(model, pose, gate_probability=probability, range_std_fraction=0)
        assert ekf.gate == pytest.approx(chi2.ppf(probability, 2))
        observation = synthetic_observation(model, 4, pose)
        _, R, _ = ekf.measurement(observation)
        _, H = ekf.predict_measurement(observation.landmark)
        range_std = math.sqrt((H @ ekf.cov @ H.T + R)[0, 0])
        # straight ahead, range and bearing are uncorrelated: a range offset has
        # d^2 = (offset / range_std)^2
        inside = 0.98 * math.sqrt(ekf.gate) * range_std
        outside = 1.02 * math.sqrt(ekf.gate) * range_std
        assert ekf.correct(synthetic_observation(model, 4, pose, range_offset=inside))
        ekf.reset(model, pose, np.diag([0.05, 0.05, 0.02]) ** 2)
        assert not ekf.correct(synthetic_observation(model, 4, pose, range_offset=outside))


def test_bearing_innovation_and_yaw_are_wrapped(model):
    # landmark 4 (x = 11.5) behind a robot at x = 13 facing +x: bearing pi, measured across the
    # cut (atan2 gives about -pi); unwrapped, the innovation of about 2 pi would be gated out
    ekf = make_ekf(model, np.array([13.0, 0.0, 0.0]))
    for offset in (0.002, -0.002):
        observation = synthetic_observation(model, 4, ekf.mean, bearing_offset=offset)
        assert abs(abs(observation.range_bearing[1]) - math.pi) < 0.003
        assert ekf.correct(observation)
    assert ekf.counters.get("gated_out", 0) == 0
    # facing the landmark with yaw just below pi, the truth just past it: the yaw crosses the cut
    truth = np.array([13.0, 0.0, -math.pi + 0.002])
    ekf = make_ekf(model, np.array([13.0, 0.0, math.pi - 0.001]), std=(0.001, 0.001, 0.02))
    assert ekf.correct(synthetic_observation(model, 4, truth))
    assert -math.pi < ekf.mean[2] < 0
    assert abs(pose_error(ekf.mean, truth)[2]) < 0.001


def test_measurement_jacobian_matches_finite_differences(model):
    ekf = make_ekf(model, np.array([3.0, -0.4, 0.3]))
    landmark = model.landmarks[1]
    _, H = ekf.predict_measurement(landmark)
    numeric = np.empty((2, 3))
    for i in range(3):
        step = np.zeros(3)
        step[i] = 1e-6
        ekf.mean = np.array([3.0, -0.4, 0.3]) + step
        plus, _ = ekf.predict_measurement(landmark)
        ekf.mean = np.array([3.0, -0.4, 0.3]) - step
        minus, _ = ekf.predict_measurement(landmark)
        numeric[:, i] = (plus - minus) / 2e-6
    np.testing.assert_allclose(H, numeric, rtol=1e-6, atol=1e-8)


def test_measurement_covariance_maps_xy_and_adds_floors(model):
    pose = np.array([5.0, 0.0, 0.0])
    observation = synthetic_observation(model, 2, pose)  # 1.2 m to the right
    bare = make_ekf(model, pose, range_std_floor=0, range_std_fraction=0, bearing_std_floor=0)
    floored = make_ekf(model, pose)
    z, R0, _ = bare.measurement(observation)
    np.testing.assert_allclose(z, observation.range_bearing)
    r = z[0]
    np.testing.assert_allclose(np.diag(R0), [1e-4, 1e-4 / r**2], rtol=1e-9)  # isotropic C
    _, R, _ = floored.measurement(observation)
    expected = np.diag(
        [
            floored.range_std_floor**2 + (floored.range_std_fraction * r) ** 2,
            floored.bearing_std_floor**2,
        ]
    )
    np.testing.assert_allclose(R - R0, expected, atol=1e-15)


def test_out_of_range_boards_are_not_used(model):
    pose = np.array([0.5, 0.0, 0.0])
    ekf = make_ekf(model, pose, max_range=8.0)
    assert not ekf.correct(synthetic_observation(model, 4, pose))  # 11 m away
    assert ekf.counters["out_of_range"] == 1


def test_options_are_checked():
    with pytest.raises(ConfigError, match=r"ekf\.gain"):
        make_estimator("ekf", gain=1.0)
    with pytest.raises(ValueError, match="gate_probability"):
        make_estimator("ekf", gate_probability=1.0)
    with pytest.raises(ValueError, match="min_range"):
        make_estimator("ekf", min_range=5.0, max_range=2.0)


# Without the camera the EKF is dead reckoning.


def test_without_frames_ekf_is_the_odometry_estimator():
    camera_off = gym.make("stsf_gym/Straight10m-v0", camera__enabled=False)
    with pytest.raises(ConfigError, match="pose source 'ekf' reads the camera"):
        PoseEstimateWrapper(camera_off, "ekf")  # the wrapper refuses it: it would be odometry
    env = PoseEstimateWrapper(camera_off, "odometry")
    try:
        obs, _ = env.reset(seed=5, options={"start_pose": [1.0, 0.2, 3.0]})
        odometry = env.estimator
        ekf = make_estimator("ekf")
        ekf.reset(sensor_model(env), odometry.mean, odometry.cov)
        for action in [[0.6, 0.4]] * 40 + [[0.8, -0.3]] * 40:  # yaw crosses pi
            obs, *_ = env.step(np.float32(action))
            ekf.update(obs, env.unwrapped.dt)
            np.testing.assert_allclose(pose_error(ekf.mean, odometry.mean), 0, atol=1e-12)
            assert -math.pi < ekf.mean[2] <= math.pi
            assert_spd(ekf.cov)
            np.testing.assert_allclose(ekf.cov, odometry.cov, rtol=1e-12, atol=1e-18)
        assert abs(odometry.mean[2]) > math.pi  # the odometry yaw did cross the cut
        assert ekf.counters.get("frames", 0) == 0 and "landmark_updates" not in ekf.counters
        assert np.trace(ekf.cov) > np.trace(env.start_cov)
    finally:
        env.close()
