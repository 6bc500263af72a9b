import warnings

import gymnasium as gym
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import stsf_gym

IDS = sorted(stsf_gym.ENV_WORLDS)


@pytest.mark.parametrize("env_id", IDS)
def test_gymnasium_check_env_warnings_as_errors(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            gym_check_env(env.unwrapped)
    finally:
        env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_sb3_check_env(env_id):
    env = gym.make(env_id)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            sb3_check_env(env.unwrapped, warn=True)
    finally:
        env.close()


def test_pan_tilt_action_dimensions(make_env):
    env = make_env(camera__control="pan_tilt", camera__enabled=False)
    assert env.action_space.shape == (4,)
    env.reset(seed=0)
    for _ in range(15):
        obs, *_ = env.step([0.0, 0.0, 0.5, -0.5])
    limits = env.unwrapped.robot.pan_tilt_limits
    assert obs["camera_pan_tilt"] == pytest.approx([0.5 * limits[0], -0.5 * limits[1]], abs=0.02)
