"""Suite ids as clients make them: a suite id carries its task (the STOP entry) whatever keyword
arguments a client passes, the follower's episodes are unchanged by that entry, and the MCL and
smoother ids pass the env checkers."""

from __future__ import annotations

import warnings

import gymnasium as gym
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import stsf_gym
from stsf_gym.config_files import SUITE_DIR

NO_CAMERA = {"camera": {"enabled": False}}
SUITE_IDS = [
    stsf_gym.suite_id(path.stem).replace("-v0", suffix)
    for path in sorted(SUITE_DIR.glob("*.yaml"))
    for suffix in ("-v0", "-Odometry-v0", "-MCL-v0")
]


@pytest.mark.parametrize("env_id", SUITE_IDS)
def test_a_suite_id_carries_its_stop_entry_whatever_a_client_passes(env_id):
    """A client's sections merge into the registered task, never replace it."""
    short = {"sim": {"max_episode_seconds": 30.0}}
    for kwargs in ({}, short, {**short, "task": {"goal_radius": 0.3}}):
        env = gym.make(env_id, **kwargs)
        try:
            assert env.get_wrapper_attr("action_layout").names[-1] == "stop", kwargs
            assert env.unwrapped.config.task.protocol == "declare"
        finally:
            env.close()


def test_the_suites_follower_episodes_are_unchanged_by_the_stop_entry():
    """The benchmark and the reproductions make their envs from the suite file and the agent's
    own needs (the follower needs none), not from the ids: the follower's cells read no STOP."""
    from stsf_gym.envs.suite import load_suite
    from stsf_gym.episode_env import make_episode_env

    env = make_episode_env(
        "generated:test", "truth", {**load_suite("corridor").episode_env, **NO_CAMERA}
    )
    try:
        assert "stop" not in env.get_wrapper_attr("action_layout").names
    finally:
        env.close()


@pytest.mark.parametrize(
    "env_id", ["stsf_gym/Suite-Corridor-MCL-v0", "stsf_gym/Corridor-Smoother-v0"]
)
def test_the_mcl_and_smoother_ids_pass_the_env_checkers(env_id):
    env = gym.make(env_id, camera={"mode": "fast"}, sim={"max_episode_seconds": 5.0})
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            warnings.filterwarnings("ignore", message=".*different from the unwrapped version")
            gym_check_env(env, skip_render_check=True)
            sb3_check_env(env, warn=True)
    finally:
        env.close()
