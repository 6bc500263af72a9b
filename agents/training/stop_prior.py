"""A fresh policy that rarely declares: the STOP entry's initial mean set by its prior.

With ``task.stop_action`` the action's last entry declares arrival when above 0. SB3's
Gaussian policy starts with every entry's mean near 0 (the action net's weights are scaled by
0.01) and its standard deviation at ``exp(log_std_init)`` = 1, so a fresh policy declares at
half its decisions and plain RL ends nearly every leg in a false STOP within a few decisions,
never reaching the states where a STOP pays (DESIGN.md, facts of 2026-11-28). Habitat's
discrete STOP is one action of four; a continuous entry needs its prior said outright.

:func:`set_stop_prior` sets the bias of the STOP entry's output to the Gaussian quantile of
``initial_stop_probability`` (the file's setting), ``sigma * Phi^-1(p)``: the fresh policy
then declares at that share of its decisions, and the spread left to explore is untouched,
so the gradient can still raise the mean where a declaration is rewarded. Only plain RL
starts from this prior; a clone's STOP entry is learnt from the expert's declarations.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import torch


def stop_mean(probability: float, std: float) -> float:
    """The mean that puts ``probability`` of a Gaussian of ``std`` above 0."""
    return std * NormalDist().inv_cdf(probability)


def set_stop_prior(policy, stop_index: int, probability: float) -> float:
    """Set the bias of ``policy``'s (an SB3 Gaussian ``ActorCriticPolicy``) STOP output so a
    fresh policy declares with ``probability`` a decision; return the bias."""
    std = math.exp(float(policy.log_std[stop_index].detach()))
    bias = stop_mean(probability, std)
    with torch.no_grad():
        policy.action_net.bias[stop_index] = bias
    return bias


def declaring_share(policy, observations: torch.Tensor, stop_index: int) -> float:
    """The mean chance over ``observations`` that ``policy`` samples a STOP above 0."""
    with torch.no_grad():
        normal = policy.get_distribution(observations).distribution
        mean, std = normal.mean[:, stop_index], normal.stddev[:, stop_index]
        return float(torch.special.ndtr(mean / std).mean())
