"""Behaviour cloning into a stable-baselines3 policy: maximum likelihood of the expert's actions.

The loss of a batch ``B`` of states ``o`` with expert actions ``a*`` is the weighted negative
log-likelihood under the policy's own action distribution,

    L = - sum_B w_i log pi(a*_i | o_i) / sum_B w_i,

read through ``policy.evaluate_actions``, so the cloned network is the very policy (mean and
spread) that RL fine-tunes afterwards. A declared stop is one decision in hundreds: its states
weigh ``stop_weight`` times the others (class re-weighting), or the mean of the ``stop`` entry
would never rise above 0 where the expert stops.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stsf_gym.envs.config import build
from stsf_gym.validation import Count, Positive


@dataclass(frozen=True)
class CloningConfig:
    """``epochs`` passes over the data in batches of ``batch_size``, Adam at
    ``learning_rate``; states where the expert stops weigh ``stop_weight``."""

    epochs: Count = 20
    batch_size: Count = 256
    learning_rate: Positive = 1.0e-3
    stop_weight: Positive = 20.0


def cloning_config(data: dict | None) -> CloningConfig:
    """A :class:`CloningConfig` from a mapping; unknown keys raise ``ConfigError``."""
    return build(CloningConfig, data or {}, "demonstrations.cloning")


def clone(
    policy,
    observations: np.ndarray,
    actions: np.ndarray,
    stop_index: int | None,
    cfg: CloningConfig,
    rng: np.random.Generator,
) -> float:
    """Fit ``policy`` (an SB3 ``ActorCriticPolicy``) to the expert's ``actions`` in
    ``observations``; return the last epoch's mean loss."""
    import torch

    obs = torch.as_tensor(observations, dtype=torch.float32)
    act = torch.as_tensor(actions, dtype=torch.float32)
    weights = np.ones(len(actions), np.float32)
    if stop_index is not None:
        weights[actions[:, stop_index] > 0] = cfg.stop_weight
    weight = torch.as_tensor(weights)
    optimizer = torch.optim.Adam(policy.parameters(), lr=cfg.learning_rate)
    policy.set_training_mode(True)
    loss_sum = 0.0
    for _ in range(cfg.epochs):
        order = torch.as_tensor(rng.permutation(len(obs)))
        loss_sum, total = 0.0, 0.0
        for batch in torch.split(order, cfg.batch_size):
            _, log_prob, _ = policy.evaluate_actions(obs[batch], act[batch])
            w = weight[batch]
            loss = -(w * log_prob).sum() / w.sum()
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            loss_sum, total = loss_sum + float(loss.detach()) * len(batch), total + len(batch)
        loss_sum /= total
    policy.set_training_mode(False)
    return loss_sum
