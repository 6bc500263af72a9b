"""The fixed-lag smoother and the floor on a synthetic trajectory with known noise.

Wheel slip, the calibration, mount and camera errors and the boards' noise are drawn from
exactly the model both assume, so the floor (batch smoother over everything) must be
consistent (NEES near its 3 degrees of freedom) and no worse than the causal smoother.
"""

import math
from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.estimators import make_estimator
from stsf_gym.estimators.odometry_model import integrate_wheel_travel
from stsf_gym.estimators.references.floor import EpisodeMeasurements, batch_floor
from stsf_gym.estimators.references.measurements import (
    CONSIDERED,
    LandmarkPose,
    OdometryLeg,
    considered_cov,
)
from stsf_gym.geometry import OdometryCalibration, compose, inverse, wrap_angle
from stsf_gym.wrappers import sensor_model

TICKS = 10**6  # fine encoders: no quantisation beyond the model
MOUNT_STD = 0.003  # m: a mount error drawn (the simulated chassis has none), and believed
BOARD_NOISE = np.diag([0.004, 0.004, 0.01]) ** 2
BOARDS = np.array(
    [[x, side * 1.2, -side * math.pi / 2] for x in np.arange(1.0, 14.0, 1.5) for side in (1, -1)]
)


@pytest.fixture(scope="module")
def model():
    env = gym.make("stsf_gym/Corridor-v0", camera__mode="fast")
    env.reset(seed=0)
    base = sensor_model(env)
    env.close()
    radius = base.calibration.wheel_radius_left
    return replace(
        base, calibration=OdometryCalibration(TICKS, radius, radius, base.calibration.wheelbase)
    )


def boards_seen(pose, k, rng) -> list[LandmarkPose]:
    seen = []
    for board in BOARDS:
        z_true = compose(inverse(pose), board)
        if not (0.5 < z_true[0] < 6.0 and abs(math.atan2(z_true[1], z_true[0])) < 0.5):
            continue
        M = np.zeros((3, CONSIDERED))
        M[:2, 3:5] = -np.eye(2)
        M[:, 5] = [0.0, z_true[0], 1.0]  # the camera heading moves the board sideways and turns it
        M[0, 6] = z_true[0]  # the focal scale scales its depth
        z = z_true + M @ k + rng.multivariate_normal(np.zeros(3), BOARD_NOISE)
        seen.append(LandmarkPose(board, z, BOARD_NOISE, M))
    return seen


def run(model, seed, frames=150):
    """One synthetic episode: (true frame poses, floor poses and covariances, smoother poses)."""
    rng = np.random.default_rng(seed)
    start, start_cov = np.zeros(3), np.diag([0.01, 0.01, 0.005]) ** 2
    k_cov = considered_cov(model, mount_std=MOUNT_STD)
    k = rng.multivariate_normal(np.zeros(CONSIDERED), k_cov)
    wheelbase = model.calibration.wheelbase
    per_tick = 2 * math.pi * model.calibration.wheel_radius_left / TICKS
    smoother = make_estimator("smoother", mount_std=MOUNT_STD)  # believes what is drawn
    smoother.reset(model, start, start_cov)
    data = EpisodeMeasurements(start, start_cov, k_cov)
    pose, truth, smoothed, leg = start.copy(), [start.copy()], [start.copy()], OdometryLeg()
    for step in range(2 * frames):
        turn = 0.02 * math.sin(step / 40)
        d_true = np.array([0.012 - turn * wheelbase / 2, 0.012 + turn * wheelbase / 2])
        pose = integrate_wheel_travel(pose, *d_true, wheelbase / (1 + k[2]))
        slip = rng.normal(0, np.sqrt(model.odometry_noise.slip_variances(*d_true)))
        reported = d_true * (1 + k[:2]) + slip
        smoother.update({"encoders": reported / per_tick, "image_new": 0}, 0.1)
        leg.add(model, *reported)
        if step % 2 == 1:
            boards = boards_seen(pose, k, rng)
            smoother.frame(boards)
            data.legs.append(leg)
            data.boards.append(boards)
            leg = OdometryLeg()
            truth.append(pose.copy())
            smoothed.append(smoother.mean.copy())
    data.records = [(i, OdometryLeg()) for i in range(len(data.boards))]
    floor, covs = batch_floor(data, covariances=True)
    return np.array(truth), floor, covs, np.array(smoothed), smoother.counters


def test_floor_consistent_and_no_worse_than_the_smoother(model):
    nees, floor_ate, smoother_ate = [], [], []
    for seed in range(4):
        truth, floor, covs, smoothed, counters = run(model, seed)
        assert counters["relocalised"] == 0 and counters["gated_out"] <= 3
        error = floor - truth
        error[:, 2] = wrap_angle(error[:, 2])
        nees += [e @ np.linalg.solve(c, e) for e, c in zip(error, covs, strict=True)]
        floor_ate.append(np.sqrt(np.mean(np.sum(error[:, :2] ** 2, axis=1))))
        smoother_ate.append(np.sqrt(np.mean(np.sum((smoothed - truth)[:, :2] ** 2, axis=1))))
    # 600 frames in 4 runs, strongly correlated in time: a loose band around 3
    assert 2.3 < np.mean(nees) < 3.8, np.mean(nees)
    assert np.mean(floor_ate) <= np.mean(smoother_ate), (floor_ate, smoother_ate)
    assert np.mean(smoother_ate) < 0.02
