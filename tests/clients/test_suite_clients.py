"""Clients run on a suite id as their users run them: TorchRL's ``GymEnv(id)`` makes and checks
the env, and rl-zoo3 trains it with evaluation during training. (The suite ids themselves:
tests/envs/test_suite_ids.py.)"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import run_rl_zoo3

NO_CAMERA = {"camera": {"enabled": False}}


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
