"""PPO that fine-tunes a cloned policy without first unlearning it.

A clone's actor is good and its critic is untrained (cloning fits the actor alone), so the
first advantages PPO computes are noise, and updates at the clone's learning rate move the
actor far from the clone before the critic has caught up: the collapse fine-tuned policies
are known for. :class:`FinetunePPO` guards the clone three ways (:class:`~stsf_gym.agents.
training.hyperparams.FinetuneConfig`): the updates of the first ``value_warmup_steps`` train
the value function alone, the actor frozen (the parameters outside the critic take no
gradient, so Adam leaves them exactly as they were); a learning rate of its own; and, after
each update, a pass over the rollout's states that lowers ``clone_kl_coef`` times
KL(clone || policy), the per-state divergence of the policy's Gaussian from the clone's, as
the auxiliary phase of phasic policy gradient distils toward a reference policy.

:class:`FreshRollouts` makes each update reproducible from its checkpoint: every rollout
starts from envs reset with a seed drawn from (run seed, timesteps) and from the learner's
random streams reseeded the same way, so a stage resumed after a kill makes the very updates
an uninterrupted one makes. The leg under way when a rollout ends is cut there, its value
bootstrapped as at a time limit.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback

CRITIC_MODULES = ("value_net", "mlp_extractor.value_net", "vf_features_extractor")


def actor_parameters(policy) -> list[torch.nn.Parameter]:
    """The parameters of ``policy`` outside its critic (the actor's, and any it shares)."""
    critic = {
        id(p)
        for name in CRITIC_MODULES
        if (module := _submodule(policy, name)) is not None
        for p in module.parameters()
    }
    return [p for p in policy.parameters() if id(p) not in critic]


def _submodule(policy, dotted: str):
    with contextlib.suppress(AttributeError):
        return policy.get_submodule(dotted)
    return None


@contextlib.contextmanager
def frozen(parameters: list[torch.nn.Parameter]) -> Iterator[None]:
    """``parameters`` take no gradient inside the block."""
    before = [p.requires_grad for p in parameters]
    for p in parameters:
        p.requires_grad_(False)
    try:
        yield
    finally:
        for p, flag in zip(parameters, before, strict=True):
            p.requires_grad_(flag)


class FinetunePPO(PPO):
    """PPO with a value warm-up and a pull toward a reference policy (:meth:`guard`); without
    them (the defaults) it updates exactly as PPO does."""

    clone = None  # the reference policy (a frozen copy of the clone), or None
    warmup_until = 0  # the updates whose rollout ends at or before this train the critic only
    clone_kl_coef = 0.0

    def guard(self, clone, warmup_until: int, clone_kl_coef: float) -> None:
        """Keep the policy near ``clone``: see the module."""
        self.clone, self.warmup_until, self.clone_kl_coef = clone, warmup_until, clone_kl_coef
        if clone is not None:
            clone.set_training_mode(False)
            for p in clone.parameters():
                p.requires_grad_(False)

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "clone", "warmup_until", "clone_kl_coef"]

    def train(self) -> None:
        """One PPO update: of the critic alone during the warm-up, else of both, then the pull
        toward the clone."""
        warming = self.num_timesteps <= self.warmup_until
        self.logger.record("finetune/value_warmup", int(warming))
        if warming:
            with frozen(actor_parameters(self.policy)):
                super().train()
            return
        super().train()
        if self.clone is not None and self.clone_kl_coef > 0:
            self.logger.record("finetune/clone_kl", self._pull_toward_clone())

    def _pull_toward_clone(self) -> float:
        """One pass over the rollout in minibatches lowering ``clone_kl_coef`` times
        :func:`mean_divergence` from the clone; its mean before each step."""
        divergences = []
        for batch in self.rollout_buffer.get(self.batch_size):
            with torch.no_grad():
                target = self.clone.get_distribution(batch.observations).distribution
            current = self.policy.get_distribution(batch.observations).distribution
            kl = mean_divergence(target, current).mean()
            self.policy.optimizer.zero_grad()
            (self.clone_kl_coef * kl).backward()
            torch.nn.utils.clip_grad_norm_(self.policy.parameters(), self.max_grad_norm)
            self.policy.optimizer.step()
            divergences.append(float(kl.detach()))
        return float(np.mean(divergences))


def widen_exploration(policy, std: float) -> None:
    """Raise each action entry's standard deviation of ``policy``'s Gaussian to at least
    ``std`` (entries already wider keep theirs)."""
    with torch.no_grad():
        policy.log_std.clamp_(min=float(np.log(std)))


def mean_divergence(reference, current) -> torch.Tensor:
    """KL(reference || current) with both Gaussians at ``current``'s deviation, per state
    summed over the entries: sum_i (mu_ref,i - mu_i)^2 / (2 sigma_i^2), the deviation taken
    as fixed; it moves the mean toward the reference's in units of the exploration noise."""
    sigma = current.stddev.detach()
    return ((reference.mean - current.mean) ** 2 / (2 * sigma**2)).sum(-1)


def stream_seed(seed: int, timesteps: int) -> int:
    """The seed of the rollout that starts at ``timesteps`` in a run seeded ``seed``."""
    return int(np.random.SeedSequence([seed, 1, timesteps]).generate_state(1)[0])


class FreshRollouts(BaseCallback):
    """Every rollout from envs reset and random streams reseeded by (seed, timesteps)."""

    def __init__(self, seed: int) -> None:
        super().__init__()
        self.seed = seed

    def _on_rollout_start(self) -> None:
        model = self.model
        model.set_random_seed(stream_seed(self.seed, model.num_timesteps))  # env seeds too
        model._last_obs = model.env.reset()
        model._last_episode_starts = np.ones(model.env.num_envs, dtype=bool)

    def _on_step(self) -> bool:
        return True
