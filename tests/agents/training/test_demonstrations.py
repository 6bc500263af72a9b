"""The demonstration stage: behaviour cloning into an SB3 policy, DAgger rounds that resume,
and the trained agent evaluated behind the same policy stack it was trained with."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch
from gymnasium import spaces
from stable_baselines3 import PPO

from stsf_gym.agents.demonstrations.cloning import CloningConfig, clone
from stsf_gym.agents.demonstrations.dagger import demonstration_config, kept_round
from stsf_gym.agents.registry import make_agent
from stsf_gym.agents.trained_agent import SB3Agent
from stsf_gym.agents.training.train import train
from stsf_gym.envs.suite import load_suite
from stsf_gym.experiments.episodes import EpisodeSpec, run_episode
from stsf_gym.io import write_json
from stsf_gym.validation import ConfigError


def test_cloning_fits_the_expert_and_its_rare_stops():
    from stable_baselines3.common.policies import ActorCriticPolicy

    rng = np.random.default_rng(0)
    obs = rng.normal(size=(3000, 4)).astype(np.float32)
    drive = np.tanh(obs[:, :2] @ np.array([[0.8, -0.3], [0.2, 0.9]]))
    stop = np.where(obs[:, 2] > 1.6, 1.0, -1.0)  # about 5 % of the states
    actions = np.column_stack([drive, stop]).astype(np.float32)
    policy = ActorCriticPolicy(
        spaces.Box(-10, 10, (4,), np.float32),
        spaces.Box(-1, 1, (3,), np.float32),
        lambda _: 1e-3,
        net_arch=[64, 64],
    )
    loss = clone(policy, obs, actions, 2, CloningConfig(epochs=30), np.random.default_rng(1))
    predicted = policy.predict(obs, deterministic=True)[0]
    assert np.sqrt(np.mean((predicted[:, :2] - drive) ** 2)) < 0.1
    stops = predicted[:, 2] > 0
    assert np.mean(stops[stop > 0]) > 0.8 and np.mean(stops[stop < 0]) < 0.05
    assert np.isfinite(loss)


def test_unknown_demonstration_keys_are_named():
    with pytest.raises(ConfigError, match="rounds"):
        demonstration_config({"rounds": -1})
    with pytest.raises(ConfigError, match="epoch"):
        demonstration_config({"cloning": {"epoch": 3}})
    with pytest.raises(ConfigError, match="keep"):
        demonstration_config({"keep": "first"})


def test_the_stage_keeps_the_last_round_or_the_best_on_validation():
    history = [{"round": r, "val_success": v} for r, v in enumerate([0.0, 1.0, 0.7, 1.0, 0.6])]
    assert kept_round(history, "last") == 4
    assert kept_round(history, "best") == 3  # the latest of the equals


TINY = {
    "demonstrations.expert_episodes": 2,
    "demonstrations.rounds": 1,
    "demonstrations.episodes_per_round": 1,
    "demonstrations.cloning.epochs": 2,
    "n_eval_episodes": 1,
    "env.sim.max_episode_seconds": 12.0,
    "train_env.sim.max_episode_seconds": 12.0,
    "train_env.task.leg_min": 1.0,
    "train_env.task.leg_max": 1.5,
}


@pytest.mark.slow
def test_the_demonstration_stage_resumes_and_its_agent_drives_behind_its_stack(tmp_path):
    out = tmp_path / "run"
    summary = train(
        "ppo", "truth", out, 0, n_envs=1, overrides=TINY, progress_bar=False, suite="corridor"
    )
    log = json.loads((out / "demonstrations.json").read_text())
    rounds = log["rounds"]
    assert [r["round"] for r in rounds] == [0, 1] and len(rounds[1]["val_episodes"]) == 1
    assert rounds[1]["samples"] > rounds[0]["samples"] > 0
    # every control step is a sample (and each reset's first state), decisions every 5 steps
    assert rounds[0]["samples"] >= rounds[0]["control_steps"] >= 4 * rounds[0]["decisions"]
    assert summary["demonstrations"]["round"] == 1 and summary["timesteps"] == 0
    kept = summary["demonstrations"]["kept_round"]
    assert summary["demonstrations"]["val_success"] == rounds[kept]["val_success"]
    recorded = json.loads((out / "train.json").read_text())["hyperparams"]["demonstrations"]
    assert recorded["keep"] == "best"  # a default is recorded: the run's fingerprint holds it
    again = train(
        "ppo", "truth", out, 0, n_envs=1, overrides=TINY, progress_bar=False, suite="corridor"
    )
    assert json.loads((out / "demonstrations.json").read_text()) == log  # resumed: nothing redone
    assert again["demonstrations"] == summary["demonstrations"]
    _resumed_after_round_0_drives_the_same_round_1(out, log, tmp_path / "resumed")
    agent = make_agent(str(out / "model.zip"))
    stop_task = {"task": {"protocol": "declare", "stop_action": True}}  # its STOP and its task
    assert isinstance(agent, SB3Agent) and agent.env_overrides() == stop_task
    env = {**load_suite("corridor").episode_env, "sim": {"max_episode_seconds": 3.0}}
    episode = run_episode(EpisodeSpec("generated:test", "truth", 0, str(out / "model.zip"), env))
    assert episode.steps <= 30 and len(episode.true_poses) == episode.steps + 1  # every step


def _resumed_after_round_0_drives_the_same_round_1(out: Path, log: dict, resumed: Path) -> None:
    """Killed after round 0 (and after round 1's data were written, before its log): the
    resumed stage collects and clones round 1 as the uninterrupted one did."""
    shutil.copytree(out, resumed)
    for finished in ("model.zip", "train.json"):
        (resumed / finished).unlink()
    (resumed / "demonstrations" / "round_1.zip").unlink()
    write_json(resumed / "demonstrations.json", {**log, "rounds": log["rounds"][:1]})
    train(
        "ppo", "truth", resumed, 0, n_envs=1, overrides=TINY, progress_bar=False, suite="corridor"
    )
    again = json.loads((resumed / "demonstrations.json").read_text())["rounds"]
    timeless = [{k: v for k, v in r.items() if k != "wall_time_s"} for r in log["rounds"]]
    assert [{k: v for k, v in r.items() if k != "wall_time_s"} for r in again] == timeless
    weights = [
        PPO.load(run / "model.zip", device="cpu").policy.state_dict() for run in (out, resumed)
    ]
    assert all(torch.equal(weights[0][k], weights[1][k]) for k in weights[0])
