import copy
import math
import pickle

import numpy as np
import pytest


def test_step_api_and_info(make_env):
    env = make_env(camera__enabled=False)
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    assert env.unwrapped.dt == pytest.approx(0.1)
    obs, reward, terminated, truncated, info = env.step(np.float32([1.0, 0.0]))
    assert env.observation_space.contains(obs)
    assert set(info) >= {"true_pose", "camera_pose", "collision", "distance_travelled"}
    assert info["camera_pose"].shape == (4, 4) and info["true_pose"].shape == (3,)
    assert reward > 0 and not terminated and not truncated  # progress along the path


def test_nominal_speed_and_real_contact(make_env):
    env = make_env(camera__enabled=False)
    env.reset(seed=0)
    cfg = env.unwrapped.config.robot
    action = np.float32([cfg.nominal_speed / cfg.max_speed, 0.0])
    for _ in range(100):
        _, _, _, _, info = env.step(action)
    assert info["distance_travelled"] / info["sim_time"] == pytest.approx(0.122, rel=0.03)


@pytest.mark.parametrize("bad", [[np.nan, 0.0], [0.0, np.inf]])
def test_nan_action_rejected(make_env, bad):
    env = make_env(camera__enabled=False)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="NaN or infinite"):
        env.step(np.float32(bad))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.float32([0.1, 0.2, 0.3]))


def test_reset_options(make_env):
    env = make_env(camera__enabled=False)
    _, info = env.reset(seed=0, options={"start_pose": [2.0, 0.3, 0.5]})
    np.testing.assert_allclose(info["true_pose"], [2.0, 0.3, 0.5], atol=1e-6)
    with pytest.raises(ValueError, match="start_pos"):
        env.reset(options={"start_pos": [0, 0, 0]})
    with pytest.raises(ValueError, match="start_pose"):
        env.reset(options={"start_pose": [0, 0]})


def test_collision_terminates_with_penalty(make_env):
    env = make_env(camera__enabled=False)
    env.reset(seed=0, options={"start_pose": [3.0, 0.0, math.pi / 2]})  # facing the north wall
    for _ in range(100):
        _, reward, terminated, truncated, info = env.step(np.float32([1.0, 0.0]))
        if terminated:
            break
    assert terminated and info["collision"] and not truncated
    assert reward < -5


def test_goal_terminates(make_env):
    env = make_env("stsf_gym/Straight10m-v0", camera__enabled=False)
    env.reset(seed=0, options={"start_pose": [9.0, 0.0, 0.0]})
    for _ in range(100):
        _, reward, terminated, _, info = env.step(np.float32([1.0, 0.0]))
        if terminated:
            break
    assert terminated and not info["collision"] and reward > 5


def test_time_limit_truncates(make_env):
    env = make_env(camera__enabled=False, sim__max_episode_seconds=1.0)
    env.reset(seed=0)
    ends = [env.step(np.float32([0.0, 0.0]))[3] for _ in range(10)]
    assert ends == [False] * 9 + [True]


def test_close_twice_and_render(make_env):
    env = make_env(render_mode="rgb_array", render__view="top", camera__enabled=False)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (360, 480, 3) and frame.dtype == np.uint8 and frame.std() > 5
    env.close()
    env.close()


def test_landmark_geometry(make_env):
    env = make_env(camera__enabled=False)
    for landmark in env.unwrapped.landmarks:
        assert landmark.square_centres.shape[1] == 3
        assert landmark.square_corners.shape[1:] == (4, 3)
        sides = np.linalg.norm(np.diff(landmark.square_corners, axis=1), axis=2)
        np.testing.assert_allclose(sides, 0.05, atol=1e-9)  # 5 cm squares
        assert landmark.centre[2] == pytest.approx(0.9)  # at the configured height
        assert landmark.board_corners[:, 2].mean() == pytest.approx(0.9)


def test_steering_change_penalty_charges_each_change_of_the_yaw_command(make_env):
    actions = [[0.5, 0.0], [0.5, 1.0], [0.5, 1.0], [0.5, -1.0]]
    rewards = {}
    for penalty in (0.0, -0.1):
        env = make_env(camera__enabled=False, reward__steering_change=penalty)
        env.reset(seed=3)
        rewards[penalty] = [env.step(np.array(a, np.float32))[1] for a in actions]
    difference = np.subtract(rewards[-0.1], rewards[0.0])
    np.testing.assert_allclose(difference, [0.0, -0.1, 0.0, -0.2], atol=1e-9)


@pytest.mark.parametrize("duplicate", [copy.deepcopy, pickle.dumps])
def test_copying_an_env_is_a_clear_error(make_env, duplicate):
    """A copy would share the PyBullet server (stepping it moved the original's robot, closing
    it disconnected the original): refused, saying why and what to do instead."""
    env = make_env("stsf_gym/Corridor-STSF-v0", camera__mode="fast")
    env.reset(seed=0)
    with pytest.raises(TypeError, match=r"cannot be copied or pickled.*gym\.make\(env\.spec\)"):
        duplicate(env)
    _, _, _, _, info = env.step(np.float32([1.0, 0.0]))  # the original is untouched
    assert info["true_pose"][0] > 0
