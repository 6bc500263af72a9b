"""The residual learner: before any update it drives exactly as the follower does, step for
step; its gate holds the follower's declaration back and the follower declares again; its stage
records ``residual+ppo`` and resumes after a kill to the weights an uninterrupted run ends with;
it trains on full routes where the clone trains on legs."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from helpers import TINY_LEARNER, interrupt_in_the_third_rollout
from stable_baselines3 import PPO

from stsf_gym.agents.follower_agent import FollowerAgent
from stsf_gym.agents.policy_stack import policy_stack
from stsf_gym.agents.rl.residual import ResidualConfig, ResidualFollower, start_as_follower
from stsf_gym.agents.training.settings import resolve_run
from stsf_gym.envs.suite import load_suite
from stsf_gym.episode_env import make_episode_env

BOUNDS = ResidualConfig().bounds
SECONDS = 40.0  # long enough for the follower to reach and declare a corridor test goal


def suite_env(seconds: float = SECONDS) -> dict:
    env = load_suite("corridor").episode_env
    return {**env, "task": {"protocol": "declare", "stop_action": True},
            "sim": {"max_episode_seconds": seconds}}  # fmt: skip


class Recorder:
    """Wraps ``env.step`` to keep every action the env is stepped with."""

    def __init__(self, env) -> None:
        self.actions: list[np.ndarray] = []
        inner = env.step
        env.step = lambda action: (self.actions.append(np.array(action)), inner(action))[1]


def test_the_untrained_residual_agent_drives_the_followers_episode_step_for_step():
    alone = make_episode_env("generated:test", "stsf", suite_env())
    under = make_episode_env("generated:test", "stsf", suite_env())
    stack = policy_stack(under, {"boards": 4, "predicted_sonar": True}, 5, BOUNDS)
    model = PPO("MlpPolicy", stack, seed=0, device="cpu")
    start_as_follower(model.policy, ResidualConfig())
    followed, corrected = Recorder(alone), Recorder(under)
    follower = FollowerAgent()
    try:
        obs, _ = alone.reset(seed=4)
        follower.begin(alone)
        while True:
            obs, _, terminated, truncated, solo = alone.step(follower.act(obs))
            if terminated or truncated:
                break
        obs, _ = stack.reset(seed=4)
        while True:
            action, _ = model.predict(obs, deterministic=True)
            obs, _, terminated, truncated, residual = stack.step(action)
            if terminated or truncated:
                break
    finally:
        alone.close()
        stack.close()
    assert len(followed.actions) == len(corrected.actions) > 100
    assert all(
        np.array_equal(a, b) for a, b in zip(followed.actions, corrected.actions, strict=True)
    )
    assert solo["stops"] == residual["stops"] and solo["success"] == residual["success"]


def test_the_residual_learner_trains_on_full_routes_where_the_clone_trains_on_legs():
    def training_task(algo: str) -> dict:
        run = resolve_run(algo, "stsf", None, 0, "corridor", None, None, None, "sparse")
        return run.train_env["task"]

    assert training_task("dagger+ppo")["leg_max"] > 0  # legs: a start on the route, a near goal
    routes = training_task("residual+ppo")
    assert routes.get("leg_max", 0.0) == 0.0 and routes["protocol"] == "declare"


def test_the_gate_holds_a_declaration_and_the_follower_declares_again():
    env = ResidualFollower(make_episode_env("generated:test", "truth", suite_env(300.0)), **BOUNDS)
    try:
        env.reset(seed=4)
        held = declared = 0
        for _ in range(4000):
            hold = -1.0 if held < 3 else 0.0  # hold the first three declarations back
            action = np.array([0.0, 0.0, hold], np.float32)
            _, _, terminated, truncated, info = env.step(action)
            held += info["declaration_held"]
            declared = info["stops"]
            if declared or terminated or truncated:
                break
        assert held == 3 and declared == 1 and info["last_stop"]["success"]
    finally:
        env.close()


def test_a_fresh_policy_starts_with_a_zero_mean_and_the_configured_exploration():
    stack = policy_stack(make_episode_env("generated:test", "truth", suite_env()), {}, 5, BOUNDS)
    try:
        model = PPO("MlpPolicy", stack, seed=0, device="cpu")
        config = ResidualConfig()
        start_as_follower(model.policy, config)
        obs = torch.as_tensor(np.stack([stack.observation_space.sample() for _ in range(8)]))
        mean = model.policy.get_distribution(obs).distribution.mean
        assert torch.equal(mean, torch.zeros_like(mean))
        stds = model.policy.log_std.exp().detach().numpy()
        assert stds == pytest.approx([config.correction_std] * 2 + [config.gate_std])
    finally:
        stack.close()


#: The tiny learner's settings for the residual stage: no demonstrations, its reward budget
#: and warm-up under ``residual.finetune``.
TINY_RESIDUAL = {
    **{k: v for k, v in TINY_LEARNER.items() if not k.startswith(("demonstrations", "finetune"))},
    "residual.finetune.timesteps": TINY_LEARNER["finetune.timesteps"],
    "residual.finetune.value_warmup_steps": TINY_LEARNER["finetune.value_warmup_steps"],
}


def train_tiny_residual(out) -> dict:
    from stsf_gym.agents.training.train import train

    return train(
        "residual+ppo", "truth", out, n_envs=1, overrides=TINY_RESIDUAL, progress_bar=False,
        suite="corridor",
    )  # fmt: skip


def _weights(path) -> dict:
    return PPO.load(path, device="cpu").policy.state_dict()


@pytest.mark.slow
def test_the_residual_stage_records_its_algo_and_resumes_to_the_same_weights(tmp_path, monkeypatch):
    from stsf_gym.agents.model_files import model_metadata
    from stsf_gym.agents.trained_agent import SB3Agent

    whole = tmp_path / "whole"
    summary = train_tiny_residual(whole)
    assert summary["algo"] == "residual+ppo" and summary["timesteps"] == 96
    run = resolve_run("residual+ppo", "truth", None, 0, "corridor", None, None, 1, "corridor")
    assert run.residual is not None
    assert model_metadata(whole / "model.zip")["residual"] == run.residual.bounds
    agent = SB3Agent(str(whole / "model.zip"))
    env = agent.make_env(sim__max_episode_seconds=2.0)
    try:
        assert env.get_wrapper_attr("action_layout").names == ("v", "w", "hold")
    finally:
        env.close()
    interrupted = tmp_path / "interrupted"
    interrupt_in_the_third_rollout(monkeypatch, lambda: train_tiny_residual(interrupted))
    resumed = train_tiny_residual(interrupted)
    assert resumed["resumed_from"] == 64 and resumed["timesteps"] == 96
    ours, theirs = _weights(interrupted / "model.zip"), _weights(whole / "model.zip")
    assert ours.keys() == theirs.keys() and all(torch.equal(ours[k], theirs[k]) for k in ours)
