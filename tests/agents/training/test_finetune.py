"""The staged trainer's reward stage: fine-tuning starts from the clone, its warm-up leaves the
actor alone, an interrupted stage resumes to the weights an uninterrupted one ends with; plain
RL on a suite learns as the RL-ready ids; ``algo`` records what ran; settings fail naming key
and file."""

from __future__ import annotations

import json
import math

import gymnasium as gym
import numpy as np
import pytest
import torch
from helpers import TINY_LEARNER, interrupt_in_the_third_rollout, train_tiny_learner
from stable_baselines3 import PPO

from stsf_gym.agents.model_files import model_metadata
from stsf_gym.agents.training.finetune import (
    FinetunePPO,
    actor_parameters,
    mean_divergence,
    widen_exploration,
)
from stsf_gym.agents.training.settings import resolve_run
from stsf_gym.agents.training.stop_prior import declaring_share, set_stop_prior
from stsf_gym.agents.training.training_log import curve_points
from stsf_gym.validation import ConfigError


def _weights(path) -> dict:
    return PPO.load(path, device="cpu").policy.state_dict()


def _same(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)


@pytest.mark.slow
def test_finetuning_starts_from_the_clone_and_resumes_to_the_same_weights(
    tiny_learner, tmp_path, monkeypatch
):
    whole, summary = tiny_learner
    assert summary["algo"] == "dagger+ppo" and summary["timesteps"] == 96
    assert json.loads((whole / "train.json").read_text())["algo"] == "dagger+ppo"
    assert model_metadata(whole / "model.zip")["algo"] == "dagger+ppo"
    kept = summary["demonstrations"]["kept_round"]
    clone = _weights(whole / "demonstrations" / f"round_{kept}.zip")
    assert _same(_weights(whole / "finetune" / "clone.zip"), clone)  # the stage's start
    assert not _same(_weights(whole / "model.zip"), clone)  # and it learnt from there
    stages = {p["stage"] for p in curve_points(whole)}
    assert stages == {"demonstrations", "reward"}  # both stages on the learning curve

    interrupted = tmp_path / "interrupted"
    interrupt_in_the_third_rollout(monkeypatch, lambda: train_tiny_learner(interrupted))
    assert not (interrupted / "model.zip").exists()
    resumed = train_tiny_learner(interrupted)
    assert resumed["resumed_from"] == 64 and resumed["timesteps"] == 96
    assert _same(_weights(interrupted / "model.zip"), _weights(whole / "model.zip"))


class _Layout(gym.Wrapper):
    """Pendulum with a STOP-like third action entry (a stand-in for the task's layout)."""

    action_layout = ("torque", "spare", "stop")

    def __init__(self) -> None:
        super().__init__(gym.make("Pendulum-v1"))
        self.action_space = gym.spaces.Box(-1, 1, (3,), np.float32)

    def step(self, action):
        return self.env.step(action[:1] * 2.0)


def test_the_value_warm_up_trains_the_critic_and_leaves_the_actor_unchanged():
    model = FinetunePPO("MlpPolicy", _Layout(), n_steps=32, batch_size=16, n_epochs=2, seed=0)
    model.guard(None, warmup_until=32, clone_kl_coef=0.0)
    actor = [p.detach().clone() for p in actor_parameters(model.policy)]
    critic = model.policy.value_net.weight.detach().clone()
    model.learn(32)
    assert all(
        torch.equal(a, p) for a, p in zip(actor, actor_parameters(model.policy), strict=True)
    )
    assert not torch.equal(critic, model.policy.value_net.weight)
    model.learn(32, reset_num_timesteps=False)  # after the warm-up both move
    assert not all(
        torch.equal(a, p) for a, p in zip(actor, actor_parameters(model.policy), strict=True)
    )


def test_the_pull_toward_the_clone_lowers_the_divergence():
    model = FinetunePPO("MlpPolicy", _Layout(), n_steps=32, batch_size=16, n_epochs=1, seed=0)
    reference = FinetunePPO("MlpPolicy", _Layout(), seed=1).policy
    model.guard(reference, warmup_until=0, clone_kl_coef=1.0)
    model.learn(32)
    first = model.logger.name_to_value.get("finetune/clone_kl")
    model.learn(32 * 20, reset_num_timesteps=False)
    assert model.logger.name_to_value["finetune/clone_kl"] < first or first is None


def test_a_clones_exploration_is_widened_and_the_pull_moves_only_the_mean():
    model = FinetunePPO("MlpPolicy", _Layout(), n_steps=32, batch_size=16, seed=0)
    with torch.no_grad():
        model.policy.log_std.copy_(torch.log(torch.tensor([0.03, 0.05, 0.3])))
    clone = FinetunePPO("MlpPolicy", _Layout(), seed=0).policy
    clone.load_state_dict(model.policy.state_dict())
    widen_exploration(model.policy, 0.1)
    assert model.policy.log_std.exp().tolist() == pytest.approx([0.1, 0.1, 0.3])
    observations = torch.zeros((4, 3))
    same_means = mean_divergence(
        clone.get_distribution(observations).distribution,
        model.policy.get_distribution(observations).distribution,
    )
    assert torch.equal(same_means, torch.zeros(4))  # the deviations differ, the means do not
    model.guard(clone, warmup_until=0, clone_kl_coef=1.0)
    model.learn(64)
    assert model.policy.log_std.exp().min() > 0.08  # no pull back to the clone's 0.03


def test_a_fresh_policy_declares_at_its_prior_share_of_decisions():
    model = PPO("MlpPolicy", _Layout(), seed=0)
    observations = torch.as_tensor(
        np.random.default_rng(0).uniform(-1, 1, (256, 3)), dtype=torch.float32
    )
    assert declaring_share(model.policy, observations, 2) > 0.3  # SB3's start: about half
    set_stop_prior(model.policy, 2, 0.0025)
    assert declaring_share(model.policy, observations, 2) == pytest.approx(0.0025, rel=0.2)


def test_plain_ppo_on_a_suite_learns_as_the_rl_ready_ids_and_records_ppo(tmp_path):
    from stable_baselines3.common.vec_env import DummyVecEnv

    from stsf_gym.agents.rl.declaration import GOES_ON_FALSE_STOP
    from stsf_gym.agents.rl.ready import rl_hyperparams
    from stsf_gym.agents.training.train import create_model
    from stsf_gym.agents.training.training_envs import make_vec_env

    plain = {"demonstrations.expert_episodes": 0, "train_env.sim.max_episode_seconds": 3.0}
    run = resolve_run("ppo", "truth", 1024, 0, "irl_corridor", None, plain, 1, "corridor")
    assert run.algo == "ppo" and not run.demonstrating
    assert run.meta["provenance"]["config"]["declaration"] == "stop-goes-on"
    assert run.train_env["task"]["false_stop_ends"] is False
    assert run.train_env["reward"]["false_stop"] == GOES_ON_FALSE_STOP
    assert run.env.get("task", {}).get("false_stop_ends", True)  # evaluation: the task itself
    ids = rl_hyperparams("corridor", "truth").training.policy_kwargs
    assert run.hp.training.policy_kwargs == ids  # the RL-ready ids' learner
    venv = make_vec_env(1, tmp_path, "train", **run.env_spec(True))
    assert isinstance(venv, DummyVecEnv)
    try:
        model = create_model(run, tmp_path, venv)
        obs = torch.as_tensor(venv.reset(), dtype=torch.float32)
        assert 0.3 < declaring_share(model.policy, obs, 2) < 0.7  # no prior: a false stop goes on
        std = torch.exp(model.policy.log_std).detach().numpy()
        assert std == pytest.approx([math.exp(ids["log_std_init"])] * 3)
        assert model.stsf_meta["algo"] == "ppo"
    finally:
        venv.close()


def test_algo_records_what_the_stages_run():
    def algo(asked, **extra):
        overrides = {**TINY_LEARNER, **extra}
        return resolve_run(asked, "truth", None, 0, "irl_corridor", None, overrides, 1, "corridor")

    assert algo("dagger").algo == "dagger" and algo("dagger").reward_steps == 0
    assert algo("dagger+ppo").algo == "dagger+ppo" and algo("dagger+ppo").reward_steps == 96
    assert algo("ppo").algo == "dagger"  # the suites' file: demonstrations, no reward budget
    assert algo("ppo", **{"demonstrations.expert_episodes": 0, "n_timesteps": 64}).algo == "ppo"


def test_settings_errors_name_the_key_and_its_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        "default: {n_envs: 1, n_timesteps: 64, policy: MlpPolicy, eval_freq: 64, "
        "n_eval_episodes: 1, checkpoint_freq: 64, n_steps: 32, finetune: {clone_kl: 0.1}}\n"
    )
    with pytest.raises(ConfigError, match=r"bad\.yaml.*finetune\.clone_kl"):
        resolve_run("ppo", "truth", None, 0, "irl_corridor", bad, None, 1, None)
    with pytest.raises(ConfigError, match=r"--set.*demonstrations\.expert_episodes"):
        overrides = {**TINY_LEARNER, "demonstrations.expert_episodes": 0}
        resolve_run("dagger+ppo", "truth", None, 0, "irl_corridor", None, overrides, 1, "corridor")
    with pytest.raises(ConfigError, match=r"--set.*finetune\.value_warmup_steps 40 must be"):
        overrides = {**TINY_LEARNER, "finetune.value_warmup_steps": 40}
        resolve_run("dagger+ppo", "truth", None, 0, "irl_corridor", None, overrides, 1, "corridor")
    with pytest.raises(ConfigError, match=r"--set: observation\.far_goal must be one of"):
        bad_suite = {**TINY_LEARNER, "observation.far_goal": "nowhere"}
        resolve_run("ppo", "truth", None, 0, "irl_corridor", None, bad_suite, 1, "corridor")
