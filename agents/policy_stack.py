"""The wrappers between a learnt policy and the pose-estimating env, built in one place.

Training (:mod:`stsf_gym.agents.training.train`) and evaluation (:class:`~stsf_gym.agents.registry.
SB3Agent`) both call :func:`policy_stack`, so a wrapper a policy was trained behind (its
observation, its decision interval) is never missing when it is evaluated.
"""

from __future__ import annotations

import gymnasium as gym

from stsf_gym.agents.decision_interval import DecisionInterval
from stsf_gym.agents.observation import ObservationConfig, PolicyObservation, observation_config
from stsf_gym.agents.rl.near_goals import LearnerNearGoals
from stsf_gym.agents.rl.residual import ResidualFollower


def policy_stack(
    env: gym.Env,
    observation: ObservationConfig | dict | None,
    decision_steps: int,
    residual: dict | None = None,
) -> gym.Env:
    """``env`` (a :class:`~stsf_gym.wrappers.PoseEstimateWrapper`) as the policy sees and
    drives it: with ``residual`` (its ``scale`` and ``hold_below``) the follower under the
    policy's correction (:class:`~stsf_gym.agents.rl.residual.ResidualFollower`), then
    :class:`PolicyObservation` with ``observation``'s settings (checked already, or a saved
    model's mapping), then :class:`DecisionInterval` of ``decision_steps`` (1: a decision
    every control step); a residual that ``acts_within`` a distance of the goals decides
    there only (:class:`~stsf_gym.agents.rl.near_goals.LearnerNearGoals`)."""
    if not isinstance(observation, ObservationConfig):
        observation = observation_config(observation)
    if residual is not None:
        env = ResidualFollower(env, **residual)
    features = PolicyObservation(env, observation)
    stack = features if decision_steps == 1 else DecisionInterval(features, decision_steps)
    near_goals = residual is not None and residual.get("acts_within") is not None
    return LearnerNearGoals(stack) if near_goals else stack
