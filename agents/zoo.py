"""Hyper-parameters for rl-zoo3 (``python -m rl_zoo3.train --conf-file stsf_gym.agents.zoo``), made
from ``configs/agents/ppo.yaml`` as ``stsf-gym train`` reads it: one section per estimating id
(every world, the generated worlds and every suite, per pose source), with
the policy observation (:class:`stsf_gym.agents.observation.PolicyObservation`) as ``env_wrapper``
and the section's env overrides as ``env_kwargs``.

```bash
python -m rl_zoo3.train --algo ppo --env stsf_gym/Corridor-STSF-v0 --gym-packages stsf_gym \\
    --conf-file stsf_gym.agents.zoo -n 20000
```

The RL-ready ids (``stsf_gym/RL-Corridor-Truth-v0``, ...) have sections too, with no wrapper:
``python -m rl_zoo3.train --algo ppo --env stsf_gym/RL-Corridor-Truth-v0 --gym-packages stsf_gym
--conf-file stsf_gym.agents.zoo`` trains the learner's task as ``gym.make`` gives it.

rl-zoo3's own options (``--eval-freq``, ``--save-freq``, ``-params``) replace the training keys
rl-zoo3 does not know (``eval_freq``, ``checkpoint_freq``, ``n_eval_episodes``). Unlike
``stsf-gym train --suite``, rl-zoo3 trains a suite id without the file's ``train_env`` (no
training legs of 2-10 m under 150 s: every episode a full route under the suite's limit) and
without the demonstration stage (``demonstrations``). PPO only:
:func:`zoo_hyperparams` gives the sections of another algorithm for a file of your own.
"""

from __future__ import annotations

import gymnasium as gym

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.agents.rl.ready import rl_hyperparams
from stsf_gym.agents.training.hyperparams import load_hyperparams, policy_kwargs_for_sb3
from stsf_gym.config_files import deep_merge

WRAPPER = "stsf_gym.agents.observation.PolicyObservation"
INTERVAL = "stsf_gym.agents.decision_interval.DecisionInterval"
SUITE_PREFIX = "stsf_gym/Suite-"  # suite ids take the file's `suites` section
ZOO_TIMESTEPS = 307_200  # the default section's PPO budget
EPISODE_ENV = "stsf_gym.episode_env:make_episode_env"  # the entry point of estimating ids
RL_ENV = "stsf_gym.agents.rl.ready:make_rl_env"  # the entry point of the RL-ready ids


def estimating_ids() -> list[str]:
    """Every registered stsf-gym id whose env carries a pose estimate (what the policy
    observation needs): each world's, the generated worlds' and each suite's, per pose source."""
    return [
        env_id
        for env_id, spec in gym.registry.items()
        if env_id.startswith("stsf_gym/") and spec.entry_point == EPISODE_ENV
    ]


def zoo_section(algo: str, env_id: str) -> dict:
    """rl-zoo3's hyper-parameters of ``env_id`` from ``configs/agents/<algo>.yaml``; a suite id's
    ``env_kwargs`` hold the suite's env settings over the file's, as ``stsf-gym train --suite``
    trains (rl-zoo3 passes them to ``gym.make``; the task's STOP entry is in the registration)."""
    suite = env_id.startswith(SUITE_PREFIX)
    hp = load_hyperparams(algo, env_id, suite=suite)
    cfg = hp.training
    registered = dict(gym.spec(env_id).kwargs.get("env") or {})
    registered.pop("generator", None)  # stays in the registered kwargs
    wrappers = [{WRAPPER: {"config": hp.observation}}]
    if cfg.decision_steps > 1:  # the learner's decision interval, outside the observation
        wrappers.append({INTERVAL: {"steps": cfg.decision_steps}})
    return {
        "policy": cfg.policy,
        "n_envs": cfg.n_envs,
        # rl-zoo3 runs RL alone (no demonstration stage): a PPO budget where the file has none
        "n_timesteps": cfg.n_timesteps or ZOO_TIMESTEPS,
        "policy_kwargs": policy_kwargs_for_sb3(cfg.policy_kwargs),
        "env_wrapper": wrappers,
        "env_kwargs": deep_merge(dict(cfg.env), registered),
        **hp.algo_kwargs,
    }


def rl_section(env_id: str) -> dict:
    """rl-zoo3's section of an RL-ready id (``stsf_gym/RL-<Suite>-<Source>-v0``): the id is the
    whole task already (input, decision interval, legs), so no wrapper and no env kwargs; the
    suite's PPO hyper-parameters, a budget of :data:`ZOO_TIMESTEPS` decisions."""
    kwargs = gym.spec(env_id).kwargs
    hp = rl_hyperparams(kwargs["suite"], kwargs["estimator"])
    cfg = hp.training
    return {
        "policy": cfg.policy,
        "n_envs": cfg.n_envs,
        "n_timesteps": ZOO_TIMESTEPS,
        "policy_kwargs": policy_kwargs_for_sb3(cfg.policy_kwargs),
        **hp.algo_kwargs,
    }


def ppo_kwargs(env_id: str) -> dict:
    """``PPO(env=..., **ppo_kwargs(env_id))``: an RL-ready id's learner as SB3 takes it (the
    policy, its keyword arguments and PPO's), the rl-zoo3 section without the budget."""
    section = rl_section(env_id)
    return {k: v for k, v in section.items() if k not in ("n_envs", "n_timesteps")}


def rl_ids() -> list[str]:
    """Every RL-ready id."""
    return [env_id for env_id, spec in gym.registry.items() if spec.entry_point == RL_ENV]


def zoo_hyperparams(algo: str) -> dict[str, dict]:
    """Every estimating id's section for ``algo``, and (PPO) every RL-ready id's."""
    sections = {env_id: zoo_section(algo, env_id) for env_id in estimating_ids()}
    if algo == "ppo":
        sections |= {env_id: rl_section(env_id) for env_id in rl_ids()}
    return sections


#: What rl-zoo3 reads from ``--conf-file stsf_gym.agents.zoo``.
hyperparams = zoo_hyperparams("ppo")
