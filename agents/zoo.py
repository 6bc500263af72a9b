"""Hyper-parameters for rl-zoo3 (``python -m rl_zoo3.train --conf-file stsf_gym.agents.zoo``), made
from ``configs/agents/ppo.yaml`` as ``stsf-gym train`` reads it: one section per estimating id, with
the policy observation (:class:`stsf_gym.agents.observation.PolicyObservation`) as ``env_wrapper``
and the section's env overrides as ``env_kwargs``.

```bash
python -m rl_zoo3.train --algo ppo --env stsf_gym/Corridor-STSF-v0 --gym-packages stsf_gym \\
    --conf-file stsf_gym.agents.zoo -n 20000
```

rl-zoo3's own options (``--eval-freq``, ``--save-freq``, ``-params``) replace the training keys
rl-zoo3 does not know (``eval_freq``, ``checkpoint_freq``, ``n_eval_episodes``). PPO only:
:func:`zoo_hyperparams` gives the sections of another algorithm for a file of your own.
"""

from __future__ import annotations

import gymnasium as gym

import stsf_gym
from stsf_gym.agents.hyperparams import load_hyperparams, policy_kwargs_for_sb3
from stsf_gym.agents.observation import observation_config

WRAPPER = "stsf_gym.agents.observation.PolicyObservation"


def estimating_ids() -> list[str]:
    """Registered ids whose env carries a pose estimate (what the policy observation needs)."""
    return [
        env_id.replace("-v0", f"-{suffix}-v0")
        for env_id in stsf_gym.ENV_WORLDS
        for suffix in stsf_gym.ESTIMATOR_IDS
        if env_id.replace("-v0", f"-{suffix}-v0") in gym.registry
    ]


def zoo_section(algo: str, env_id: str) -> dict:
    """rl-zoo3's hyper-parameters of ``env_id`` from ``configs/agents/<algo>.yaml``."""
    hp = load_hyperparams(algo, env_id)
    cfg = hp.training
    return {
        "policy": cfg.policy,
        "n_envs": cfg.n_envs,
        "n_timesteps": cfg.n_timesteps,
        "policy_kwargs": policy_kwargs_for_sb3(cfg.policy_kwargs),
        "env_wrapper": [{WRAPPER: {"config": observation_config(cfg.observation)}}],
        "env_kwargs": dict(cfg.env),
        **hp.algo_kwargs,
    }


def zoo_hyperparams(algo: str) -> dict[str, dict]:
    """Every estimating id's section for ``algo``."""
    return {env_id: zoo_section(algo, env_id) for env_id in estimating_ids()}


#: What rl-zoo3 reads from ``--conf-file stsf_gym.agents.zoo``.
hyperparams = zoo_hyperparams("ppo")
