"""Clients, third round, run as their users run them: a suite id carries its task (the STOP
entry) whatever keyword arguments a client passes; rl-zoo3 trains a suite id with evaluation
during training; TorchRL's ``GymEnv(id)`` makes and checks the env; a policy stack survives its
own JSON spec; the MCL and smoother ids pass the env checkers."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils.env_checker import check_env as gym_check_env
from helpers import run_rl_zoo3
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import stsf_gym
from stsf_gym.agents.observation import PolicyObservation, observation_config
from stsf_gym.yaml_layers import SUITE_DIR

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


def test_a_policy_stack_survives_its_own_json_spec():
    env = gym.make("stsf_gym/Suite-Corridor-Truth-v0", **NO_CAMERA)
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


@pytest.mark.slow
def test_torchrl_gym_env_makes_and_checks_a_suite_id():
    """TorchRL passes ``frameskip`` first and retries without it on the ``TypeError`` that
    names it; then its spec check and a rollout."""
    from torchrl.envs import GymEnv
    from torchrl.envs.utils import check_env_specs

    env = GymEnv("stsf_gym/Suite-Corridor-Truth-v0", **NO_CAMERA)
    try:
        assert tuple(env.action_spec.shape) == (3,)  # v, w and STOP
        check_env_specs(env, seed=0)
        assert env.rollout(3)["next", "pose"].shape[-1] == 3
    finally:
        env.close()


@pytest.mark.slow
def test_rl_zoo3_trains_a_suite_id_with_evaluation_during_training(tmp_path):
    """rl-zoo3's evaluation env is built from ``--eval-env-kwargs`` alone and ``--env-kwargs``
    replaces the zoo file's: both keep the STOP entry, from the registration."""
    env_id = "stsf_gym/Suite-Corridor-Truth-v0"
    evaluation = ["--eval-freq", "64", "--eval-episodes", "1"]
    kwargs = ["--env-kwargs", "camera:{'enabled':False}"]
    kwargs += ["--eval-env-kwargs", "camera:{'enabled':False}", "sim:{'max_episode_seconds':10.0}"]
    result = run_rl_zoo3(env_id, tmp_path, *evaluation, *kwargs)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    (run,) = tmp_path.glob(f"ppo/{env_id.replace('/', '-')}_1")
    evaluations = np.load(run / "evaluations.npz")
    assert list(evaluations["timesteps"]) == [64, 128]
    from stable_baselines3 import PPO

    for model in run.glob("*.zip"):  # the final model and the best evaluated one
        assert PPO.load(model, device="cpu").action_space.shape == (3,), model.name
