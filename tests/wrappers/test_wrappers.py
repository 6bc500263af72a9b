import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from stsf_gym.estimators import make_estimator
from stsf_gym.estimators.odometry_model import integrate_wheel_travel
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import PoseEstimateWrapper

ESTIMATING_IDS = [
    "stsf_gym/Corridor-Odometry-v0",
    "stsf_gym/Straight10m-Odometry-v0",
    "stsf_gym/Corridor-STSF-v0",
    "stsf_gym/Corridor-Conventional-v0",
    "stsf_gym/Straight10m-EKF-v0",
]


@pytest.mark.parametrize("env_id", ESTIMATING_IDS)
def test_estimating_ids_pass_both_checkers(env_id):
    env = gym.make(env_id)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            # checking the wrapper itself is the point here, so only that notice is allowed
            warnings.filterwarnings("ignore", message=".*different from the unwrapped version")
            gym_check_env(env)
            sb3_check_env(env, warn=True)
    finally:
        env.close()


def test_odometry_estimate_is_dead_reckoning_with_growing_covariance(make_env):
    env = PoseEstimateWrapper(make_env(camera__enabled=False), "odometry")
    obs, _ = env.reset(seed=4, options={"start_pose": [1.0, 0.2, 0.1]})
    np.testing.assert_allclose(obs["pose"], [1.0, 0.2, 0.1], atol=1e-6)
    calibration = env.unwrapped.odometry_calibration
    manual, traces = np.array([1.0, 0.2, 0.1]), [np.trace(obs["pose_cov"].reshape(3, 3))]
    for action in [[0.6, 0.3]] * 30 + [[0.8, -0.2]] * 30:
        obs, *_ = env.step(np.float32(action))
        manual = integrate_wheel_travel(
            manual, *calibration.wheel_travel(obs["encoders"]), calibration.wheelbase
        )
        traces.append(np.trace(obs["pose_cov"].reshape(3, 3)))
    np.testing.assert_allclose(obs["pose"], manual, atol=1e-5)
    # it grows while the robot turns one way; turning back undoes part of the heading drift a
    # wrong wheelbase caused (a fixed calibration error, not noise), so it may then shrink
    assert np.all(np.diff(traces[:31]) > 0) and traces[-1] > traces[0]
    cov = obs["pose_cov"].reshape(3, 3)
    np.testing.assert_allclose(cov, cov.T, atol=1e-9)
    assert np.all(np.linalg.eigvalsh(cov) > 0)


def test_unknown_estimator_and_option_are_named(make_env):
    with pytest.raises(ValueError, match="'kalman'"):
        make_estimator("kalman")
    with pytest.raises(ConfigError, match=r"odometry\.gain"):
        PoseEstimateWrapper(make_env(camera__enabled=False), "odometry", gain=2)
