"""Gymnasium's wrapper conventions: hand-built stacks pass both env checkers and re-create
from their ``spec``."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils.env_checker import check_env as gym_check_env
from helpers import id_matrix, registered_ids
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from stsf_gym.agents.observation import PolicyObservation, observation_config
from stsf_gym.wrappers import POSE_SOURCES, PoseEstimateWrapper


@pytest.mark.parametrize("estimator", POSE_SOURCES)
def test_hand_built_wrapper_passes_both_checkers(make_env, estimator):
    env = PoseEstimateWrapper(make_env(), estimator)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # checking the wrapper itself is the point here, so only that notice is allowed
        warnings.filterwarnings("ignore", message=".*different from the unwrapped version")
        gym_check_env(env)
        sb3_check_env(env, warn=True)


def _rollout(env, seed: int = 3, steps: int = 12) -> list[dict]:
    obs, _ = env.reset(seed=seed)
    history = [obs]
    for _ in range(steps):
        obs, *_ = env.step(np.float32([0.8, 0.2]))
        history.append(obs)
    return history


def test_spec_recreates_a_hand_built_stack(make_env):
    env = PolicyObservation(
        PoseEstimateWrapper(make_env(camera__mode="fast"), "stsf", start_std=(0.02, 0.02, 0.01))
    )
    names = [w.name for w in env.spec.additional_wrappers]
    assert names[-2:] == ["PoseEstimateWrapper", "PolicyObservation"]
    assert env.spec.additional_wrappers[-2].kwargs == {
        "estimator": "stsf",
        "start_std": [0.02, 0.02, 0.01],  # as JSON gives it back
    }
    again = gym.make(EnvSpec.from_json(env.spec.to_json()))
    try:
        assert isinstance(again, PolicyObservation)
        assert isinstance(again.env, PoseEstimateWrapper)
        assert again.unwrapped.config.camera.mode == "fast"
        for a, b in zip(_rollout(env), _rollout(again), strict=True):
            np.testing.assert_array_equal(a, b)
    finally:
        again.close()


def test_spec_of_a_registered_estimating_id_does_not_wrap_twice(make_env):
    env = make_env("stsf_gym/Straight10m-EKF-v0", camera__mode="fast")
    again = gym.make(env.spec)
    try:
        depth = 0
        inner = again
        while isinstance(inner, gym.Wrapper):
            depth += isinstance(inner, PoseEstimateWrapper)
            inner = inner.env
        assert depth == 1
    finally:
        again.close()


@pytest.mark.parametrize("env_id", id_matrix(registered_ids()))
def test_spec_json_round_trip_on_every_id(env_id):
    """``EnvSpec.from_json(env.spec.to_json())`` gives the same spec, and ``gym.make`` takes it
    (a tuple recorded by a wrapper came back a list: every estimating id failed)."""
    env = gym.make(env_id, camera={"mode": "fast"})
    try:
        spec = EnvSpec.from_json(env.spec.to_json())
        assert spec == env.spec
        gym.make(spec).close()
    finally:
        env.close()


def test_a_policy_stack_survives_its_own_json_spec():
    env = gym.make("stsf_gym/Suite-Corridor-Truth-v0", camera={"enabled": False})
    env = PolicyObservation(env, observation_config({"lookahead": [0.0, 1.0], "scale": 2.0}))
    again = gym.make(EnvSpec.from_json(env.spec.to_json()))
    try:
        assert again.get_wrapper_attr("config") == env.get_wrapper_attr("config")
        first, _ = env.reset(seed=3)
        second, _ = again.reset(seed=3)
        np.testing.assert_array_equal(first, second)
    finally:
        env.close()
        again.close()
