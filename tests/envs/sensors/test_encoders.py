import math

import numpy as np
import pytest
from helpers import NOISE_FREE_ENCODERS

from stsf_gym.envs.config import load_config
from stsf_gym.envs.sensors.encoders import WheelEncoders
from stsf_gym.estimators.odometry_model import integrate_wheel_travel


def dead_reckon(env, actions, seed=0):
    obs, info = env.reset(seed=seed)
    calibration = env.unwrapped.odometry_calibration
    estimate = info["true_pose"].copy()
    for action in actions:
        obs, _, terminated, truncated, info = env.step(np.float32(action))
        d_left, d_right = calibration.wheel_travel(obs["encoders"])
        estimate = integrate_wheel_travel(estimate, d_left, d_right, calibration.wheelbase)
        if terminated or truncated:
            break
    return estimate, info["true_pose"]


def test_noise_free_dead_reckoning_tracks_truth(make_env):
    env = make_env("stsf_gym/Straight10m-v0", camera__enabled=False, **NOISE_FREE_ENCODERS)
    actions = [[0.8, 0.0]] * 150 + [[0.4, 0.5]] * 40 + [[0.8, -0.3]] * 100  # about 6 m, turns
    estimate, truth = dead_reckon(env, actions)
    assert np.hypot(*(estimate[:2] - truth[:2])) < 0.01
    total_turn = 0.5 * 40 * 0.1 + 0.3 * 100 * 0.1  # rad commanded, at max_yaw_rate 1 rad/s
    assert abs(math.remainder(estimate[2] - truth[2], math.tau)) < 0.004 * total_turn


def test_default_noise_drifts_about_40cm_over_10m_straight():
    """The encoder model alone, on a perfectly straight 10 m at 12.2 cm/s, over many robots."""
    cfg = load_config()
    encoders = WheelEncoders(cfg.encoders, cfg.robot.wheel_radius, cfg.robot.wheelbase)
    r, dt, v = cfg.robot.wheel_radius, cfg.sim.control_dt, cfg.robot.nominal_speed
    steps = round(10.0 / (v * dt))
    errors = []
    for seed in range(200):
        rng = np.random.default_rng(seed)
        encoders.reset(np.zeros(2), rng)
        calibration, pose = encoders.calibration, np.zeros(3)
        for k in range(1, steps + 1):
            ticks = encoders.read(np.full(2, k * v * dt / r), rng)
            pose = integrate_wheel_travel(
                pose, *calibration.wheel_travel(ticks), calibration.wheelbase
            )
        errors.append(np.hypot(pose[0] - 10.0, pose[1]))
    assert np.median(errors) == pytest.approx(0.40, abs=0.08)


def test_tick_deltas_are_quantised_and_sum_exactly(make_env):
    env = make_env(camera__enabled=False, **NOISE_FREE_ENCODERS)
    env.reset(seed=0)
    total = np.zeros(2, np.int64)
    for _ in range(50):
        obs, *_ = env.step(np.float32([0.5, 0.3]))
        assert obs["encoders"].dtype == np.int64
        total += obs["encoders"]
    angles = env.unwrapped.robot.wheel_angles()
    expected = np.floor(angles * env.unwrapped.odometry_calibration.ticks_per_rev / (2 * math.pi))
    np.testing.assert_array_equal(total, expected)


@pytest.mark.parametrize("seed", range(10))
def test_tick_kernel_is_the_numpy_expressions_of_both_wheels(seed):
    """The compiled tick count gives, to the bit, the array expressions it replaced: rotation,
    slip, counts and the whole ticks crossed, over many reads of rotations either way."""
    from stsf_gym.envs.sensors.encoders import _ticks

    rng = np.random.default_rng(seed)
    slip_std, ticks_per_rev = 0.01, 360
    counts, last = rng.uniform(-50, 50, 2), rng.uniform(-3, 3, 2)
    expected_counts = counts.copy()
    for _ in range(50):
        angles, normal = last + rng.normal(0, 0.3, 2), rng.normal(size=2)
        rotation = angles - last
        slip = normal * slip_std * np.sqrt(np.abs(rotation))
        before = np.floor(expected_counts)
        expected_counts += (rotation + slip) * ticks_per_rev / (2 * math.pi)
        expected = (np.floor(expected_counts) - before).astype(np.int64)
        got = _ticks(angles, last, counts, normal, slip_std, ticks_per_rev)
        assert got.dtype == np.int64
        np.testing.assert_array_equal(got, expected)
        np.testing.assert_array_equal(counts, expected_counts)
        last = angles
