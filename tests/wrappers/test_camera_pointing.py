"""One job per wrapper: the estimate wrapper adds ``pose`` and ``pose_cov`` and leaves the
action and the camera alone; the pointing wrapper over it takes the pan entry out of the
action, points the camera and runs the unknown-start search; ``make_episode_env`` stacks
both, as a hand-built stack does."""

from __future__ import annotations

import numpy as np
import pytest

from stsf_gym.episode_env import (
    EPISODE_DEFAULTS,
    episode_settings,
    make_episode_env,
    resolved_config,
)
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import CameraPointingWrapper, PoseEstimateWrapper

PAN = {"camera__control": "pan", "camera__mode": "fast"}
START = {"start_pose": [2.0, 0.0, 0.0]}  # board 1 ahead on the left


def test_the_estimate_wrapper_adds_the_pose_and_leaves_action_and_camera_alone(make_env):
    bare = make_env(**PAN)
    env = PoseEstimateWrapper(make_env(**PAN), "odometry")
    assert env.action_space == bare.action_space and env.action_space.shape == (3,)
    assert set(env.observation_space.spaces) == {*bare.observation_space.spaces, "pose", "pose_cov"}
    seen, wrapped = bare.reset(seed=2, options=START)[0], env.reset(seed=2, options=START)[0]
    for step in range(8):
        action = np.float32([0.5, 0.1, 0.6])  # the pan entry is the agent's, passed on as it is
        for key, value in seen.items():
            np.testing.assert_array_equal(wrapped[key], value, err_msg=f"{key}, step {step}")
        seen, wrapped = bare.step(action)[0], env.step(action)[0]
    assert wrapped["camera_pan_tilt"][0] > 0.1  # turned where the agent said


def test_the_pointing_wrapper_takes_the_pan_entry_and_points_the_camera(make_env):
    env = CameraPointingWrapper(PoseEstimateWrapper(make_env(**PAN), "truth"))
    assert env.action_space.shape == (2,) and env.action_layout.names == ("v", "w")
    assert env.env.action_space.shape == (3,)
    env.reset(seed=0, options=START)
    for _ in range(10):
        obs, *_ = env.step(np.float32([0.5, 0.0]))
    assert env.pointer.target == 1
    assert obs["camera_pan_tilt"][0] > 0.5 and 1 in env.unwrapped.landmarks_in_view()
    assert not env.searching


def test_pointing_needs_a_pan_camera_and_an_estimate(make_env):
    with pytest.raises(ConfigError, match=r"camera\.control"):
        CameraPointingWrapper(PoseEstimateWrapper(make_env(camera__mode="fast"), "truth"))
    with pytest.raises(ValueError, match="it needs a PoseEstimateWrapper under it"):
        CameraPointingWrapper(make_env(**PAN))


def test_a_hand_built_stack_is_the_episode_env(make_env):
    built = make_episode_env("irl_corridor", "stsf", {"camera__mode": "fast"})
    hand = CameraPointingWrapper(PoseEstimateWrapper(make_env(**PAN), "stsf"))
    try:
        assert isinstance(built, CameraPointingWrapper)
        assert isinstance(built.env, PoseEstimateWrapper)
        assert built.action_space == hand.action_space
        a, b = built.reset(seed=1)[0], hand.reset(seed=1)[0]
        for _ in range(30):
            for key in a:
                np.testing.assert_array_equal(a[key], b[key], err_msg=key)
            a, b = built.step(np.float32([0.6, 0.1]))[0], hand.step(np.float32([0.6, 0.1]))[0]
    finally:
        built.close()


def test_the_unknown_start_search_is_the_pointing_wrappers(make_env):
    env = make_episode_env("irl_corridor", "mcl", {"camera__mode": "fast"})
    try:
        obs, _ = env.reset(seed=0, options={"unknown_start": True})
        assert env.searching and env.pointer.target is None
        assert np.sqrt(obs["pose_cov"][0]) > 1.0  # the prior spread over the map
        for _ in range(5):  # the camera sweeps (a sine), whatever the estimate says
            obs, *_ = env.step(np.float32([0.0, 0.0]))
        assert env.searching and obs["camera_pan_tilt"][0] > 0.1
        env.reset(seed=0)
        assert not env.searching
    finally:
        env.close()
    alone = PoseEstimateWrapper(make_env(**PAN), "mcl")  # the estimate's part: the prior only
    obs, _ = alone.reset(seed=0, options={"unknown_start": True})
    assert np.sqrt(obs["pose_cov"][0]) > 1.0 and not hasattr(alone, "searching")


def test_the_episode_layering_is_written_once():
    assert episode_settings(None) == EPISODE_DEFAULTS == {"camera__control": "pan"}
    assert episode_settings({"camera__control": "none"}) == {"camera__control": "none"}
    env = make_episode_env("irl_corridor", "odometry", {"camera__control": "none"})
    try:  # no pan axis: nothing to point, the estimate wrapper is the stack
        assert isinstance(env, PoseEstimateWrapper) and env.action_space.shape == (2,)
    finally:
        env.close()
    camera = resolved_config("irl_corridor", "odometry")["env"]["camera"]  # read, not built
    assert camera["control"] == "pan"
    camera = resolved_config("irl_corridor", "odometry", {"camera": {"control": "none"}})
    assert camera["env"]["camera"]["control"] == "none"


def test_camera_pointing_with_no_estimate_under_it_says_what_it_needs(make_env):
    from stsf_gym.wrappers.pointing import CameraPointingWrapper

    env = make_env("stsf_gym/Corridor-v0", camera={"mode": "fast", "control": "pan"})
    with pytest.raises(ValueError, match="it needs a PoseEstimateWrapper under it"):
        CameraPointingWrapper(env)


def test_an_estimate_over_an_estimate_is_refused(make_env):
    from stsf_gym.wrappers import PoseEstimateWrapper

    env = make_env("stsf_gym/Corridor-Truth-v0", camera={"mode": "fast"})
    with pytest.raises(ValueError, match="has 'pose' already \\(pose source 'truth'\\)"):
        PoseEstimateWrapper(env, "odometry")
