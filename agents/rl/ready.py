"""RL-ready envs: ``stsf_gym/RL-<Suite>-<Source>-v0``, the learner's task as ``gym.make`` gives it.

A suite id (``stsf_gym/Suite-Sparse-STSF-v0``) is the benchmark's episode: a ``Dict``
observation with the camera's image, a 0.1 s control step and whole routes of 20-45 m. What
``stsf-gym train`` learns on is built on top of it, and an RL user's fifteen lines should get
the same from ``gym.make`` alone. :func:`make_rl_env` builds it, in the trainer's own settings
(``configs/agents/ppo.yaml``, section ``suites``, read by
:func:`~stsf_gym.agents.training.hyperparams.load_hyperparams`, so the two cannot drift):

- the policy's flat ``Box`` input (:class:`~stsf_gym.agents.observation.PolicyObservation`,
  the file's ``observation`` settings), no image;
- a decision every ``decision_steps`` control steps (0.5 s,
  :class:`~stsf_gym.agents.decision_interval.DecisionInterval`);
- ``split="train"`` (default): training legs on the suite's train worlds (``train_env``:
  a start on the route, one goal 2-10 m ahead); ``"val"`` / ``"test"``: full routes on the
  held-out worlds, the benchmark's task;
- the camera switched off where the pose source reads none (the true pose, odometry);
- ``declaration``: how arrival is declared on the training legs
  (:mod:`~stsf_gym.agents.rl.declaration`; the evaluation splits keep the task as it is).

``max_episode_steps`` of every id is :func:`episode_decisions`: the suite's time limit in
decisions, which bounds a full route; a training leg ends sooner, at its own time limit
(``train_env.sim.max_episode_seconds``), truncated as at the id's. ``info["is_success"]``
is set at an episode's end (SB3's ``evaluate_policy`` and ``EvalCallback`` count it).
"""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import Any

import gymnasium as gym

from stsf_gym.agents.observation import observation_config
from stsf_gym.agents.policy_stack import policy_stack
from stsf_gym.agents.rl.declaration import (
    DEFAULT_DECLARATION,
    DiscreteActions,
    GradedFalseStop,
    WeanedFalseStop,
)
from stsf_gym.agents.rl.declaration import declaration as design_of
from stsf_gym.agents.training.hyperparams import Hyperparams, load_hyperparams
from stsf_gym.agents.training.settings import suite_env
from stsf_gym.agents.training.training_envs import env_id_for
from stsf_gym.config_files import deep_merge
from stsf_gym.envs.config import EnvConfig, RewardConfig, load_config
from stsf_gym.envs.generated_env import generated_label
from stsf_gym.episode_env import make_episode_env
from stsf_gym.estimators import estimator_class
from stsf_gym.wrappers import TRUTH

SPLITS = ("train", "val", "test")


def rl_hyperparams(suite: str, estimator: str) -> Hyperparams:
    """The trainer's settings for ``suite`` driven on ``estimator`` (PPO's file: its ``suites``
    and ``rl-ready`` sections and the suite id's section)."""
    return load_hyperparams(
        "ppo", env_id_for(generated_label("train"), estimator, suite), rl_ready=True
    )


def reads_camera(estimator: str) -> bool:
    """Whether pose source ``estimator`` reads the camera (the true pose reads nothing)."""
    return estimator != TRUTH and "camera" in estimator_class(estimator).sensors


def rl_settings(suite: str, estimator: str, split: str, design: str) -> tuple[dict, Hyperparams]:
    """The env settings of an RL-ready env and the trainer settings they came from."""
    if split not in SPLITS:
        raise ValueError(f"split must be one of {SPLITS}, got {split!r}")
    hp = rl_hyperparams(suite, estimator)
    env = suite_env(hp, suite)
    if split == "train":
        env = deep_merge(deep_merge(env, hp.training.train_env), design_of(design).training_env())
    if not reads_camera(estimator):
        env = deep_merge(env, {"camera": {"enabled": False}})
    return env, hp


def evaluation_config(suite: str, estimator: str = TRUTH) -> tuple[EnvConfig, Hyperparams]:
    """The env config of the suite's full routes (its val and test splits) and the trainer
    settings they came from."""
    env, hp = rl_settings(suite, estimator, "test", DEFAULT_DECLARATION)
    return load_config(**{k: v for k, v in env.items() if k != "generator"}), hp


def episode_decisions(suite: str, estimator: str = TRUTH) -> int:
    """The most decisions an episode of the suite's RL-ready ids takes: its time limit over the
    decision period (the legs' limit is shorter)."""
    config, hp = evaluation_config(suite, estimator)
    period = config.sim.control_dt * hp.training.decision_steps
    return math.ceil(config.sim.max_episode_seconds / period - 1e-9)


def task_reward(suite: str, estimator: str = TRUTH) -> RewardConfig:
    """The reward of the suite's full routes, which the training legs' designs change."""
    return evaluation_config(suite, estimator)[0].reward


def make_rl_env(
    suite: str,
    estimator: str,
    split: str = "train",
    declaration: str = DEFAULT_DECLARATION,
    observation: dict | None = None,
    **overrides: Any,
) -> gym.Env:
    """The RL-ready env of ``suite`` on pose source ``estimator`` (see the module):
    ``observation`` settings over the file's (``{"boards": 3, "predicted_sonar": True}``:
    :class:`~stsf_gym.agents.observation.ObservationConfig`), ``overrides`` env settings over
    the id's (``sim__max_episode_seconds=60``, ...)."""
    env, hp = rl_settings(suite, estimator, split, declaration)
    features = observation_config({**asdict(hp.observation), **(observation or {})})
    design = design_of(declaration)
    estimating = make_episode_env(generated_label(split), estimator, env, **overrides)
    if design.graded and split == "train":
        progress = estimating.unwrapped.config.reward.progress  # type: ignore[attr-defined]
        estimating = GradedFalseStop(estimating, progress)
    if design.weaned and split == "train":
        routes = task_reward(suite, estimator).false_stop  # the task's, as its routes end
        estimating = WeanedFalseStop(estimating, design.false_stop, routes, design.wean_false_stops)
    stack = policy_stack(estimating, features, hp.training.decision_steps)
    return DiscreteActions(stack) if design.discrete else stack
