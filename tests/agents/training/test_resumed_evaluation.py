"""A resumed PPO run evaluates at the timesteps an uninterrupted one does, and keeps the best
mean reward it had (:mod:`stsf_gym.agents.training.resumed_eval`). On CartPole: the callback's
arithmetic, not the corridor, is under test."""

from __future__ import annotations

import gymnasium as gym
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.monitor import Monitor

from stsf_gym.agents.training.resumed_eval import ResumableEvalCallback
from stsf_gym.agents.training.training_log import EvalLog

N_ENVS, N_STEPS, EVAL_CALLS = 2, 32, 64  # an update every 64 timesteps, evaluations every 128


def learn(model: PPO, steps: int, out) -> ResumableEvalCallback:
    """``steps`` more timesteps of ``model`` under the evaluation callback; the callback."""
    callback = ResumableEvalCallback(
        Monitor(gym.make("CartPole-v1")),
        out=out,
        log_path=str(out / "eval"),
        n_eval_episodes=1,
        eval_freq=EVAL_CALLS,
        callback_after_eval=EvalLog(out),
        verbose=0,
    )
    model.learn(steps, callback=callback, reset_num_timesteps=False)
    return callback


def new_model() -> PPO:
    """PPO on CartPole, with the run record the trainer's models carry (EvalLog reads it)."""
    env = make_vec_env("CartPole-v1", n_envs=N_ENVS, seed=0)
    model = PPO("MlpPolicy", env, n_steps=N_STEPS, batch_size=64, n_epochs=1, seed=0, device="cpu")
    model.stsf_meta = {"wall_time_s": 0.0}
    return model


def test_a_resumed_run_evaluates_at_the_uninterrupted_runs_timesteps(tmp_path):
    whole = learn(new_model(), 512, tmp_path / "whole")
    assert list(whole.evaluations_timesteps) == [128, 256, 384, 512]

    first = new_model()
    before = learn(first, 192, tmp_path / "resumed")  # stopped after 3 updates
    assert list(before.evaluations_timesteps) == [128]
    first.save(tmp_path / "checkpoint.zip")
    resumed = PPO.load(
        tmp_path / "checkpoint.zip", env=make_vec_env("CartPole-v1", n_envs=N_ENVS), device="cpu"
    )
    after = learn(resumed, 512 - 192, tmp_path / "resumed")
    assert list(after.evaluations_timesteps) == [256, 384, 512]  # SB3's own: 320, 448
    assert after.best_mean_reward >= before.best_mean_reward  # the best before is remembered
