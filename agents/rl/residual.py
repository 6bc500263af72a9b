"""A residual learner over the path follower: the follower's action plus a bounded learnt
correction, and a learnt gate over the follower's declarations.

Residual policy learning (Silver et al. 2018; Johannink et al. 2019): the policy does not
replace a working controller, it corrects it. :class:`ResidualFollower` sits over the
pose-estimating env (beneath the policy's observation and decision interval) and runs the
scripted follower (:class:`~stsf_gym.agents.follower_agent.FollowerAgent`) on every control
step, as the follower runs when it drives alone. The policy's action is ``[dv, dw, hold]``
(``action_layout``: ``v, w, hold``), each in ``[-1, 1]``:

- the env is driven by the follower's ``[v, w]`` plus ``scale`` times ``[dv, dw]`` (clipped
  to the action box): at ``scale`` = 0.5, 0.125 m/s and 0.5 rad/s, enough to stop, back off
  or turn to a board, never more than half the robot's range off the follower's command;
- when the follower declares arrival (its STOP entry), the declaration goes through unless
  ``hold`` is below ``hold_below``; held, the robot stands as the follower stood, and the
  follower heads for the same goal again, so it declares again at the next step unless held.

The observation gains ``follower_action``: the follower's action for the state just reached
(``[v, w, stop]``), which the policy's input reads (what it corrects, and when the follower
would declare). A policy whose mean action is 0 (:func:`start_as_follower`) therefore drives
exactly as the follower does, step for step. With ``acts_within``, :attr:`near_goal` says
whether the estimated position is within that many metres of the current goal, where
:class:`~stsf_gym.agents.rl.near_goals.LearnerNearGoals` lets the policy decide.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated

import gymnasium as gym
import numpy as np
import torch
from gymnasium import spaces

from stsf_gym.agents.follower_agent import FollowerAgent
from stsf_gym.envs.action_layout import ActionLayout
from stsf_gym.validation import Positive, Range

PROPOSAL = "follower_action"  # the observation key of the follower's action


@dataclass(frozen=True)
class ResidualConfig:
    """The residual's bounds (``residual:`` of the hyper-parameter file): ``scale`` of the
    correction in action units, ``hold_below`` the gate's threshold, and the standard
    deviations a fresh policy explores with (``correction_std`` on ``dv, dw``, ``gate_std`` on
    ``hold``: a gate at 0 with 0.5 holds a declaration with probability 0.16); ``acts_within``
    the metres from the goal within which the policy decides (None: everywhere)."""

    scale: Annotated[float, Range(gt=0, le=2)] = 0.5
    hold_below: Annotated[float, Range(ge=-1, le=1)] = -0.5
    correction_std: Annotated[float, Range(gt=0, le=1)] = 0.3
    gate_std: Annotated[float, Range(gt=0, le=1)] = 0.5
    acts_within: Positive | None = None

    @property
    def bounds(self) -> dict:
        """What the policy stack needs (:class:`ResidualFollower`'s arguments)."""
        near = {} if self.acts_within is None else {"acts_within": self.acts_within}
        return {"scale": self.scale, "hold_below": self.hold_below, **near}


class ResidualFollower(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """The follower's action corrected by the policy's (see the module)."""

    def __init__(
        self,
        env: gym.Env,
        scale: float = 0.5,
        hold_below: float = -0.5,
        acts_within: float | None = None,
    ) -> None:
        gym.utils.RecordConstructorArgs.__init__(
            self, scale=scale, hold_below=hold_below, acts_within=acts_within
        )
        gym.Wrapper.__init__(self, env)
        inner = env.get_wrapper_attr("action_layout")
        if tuple(inner.names) != ("v", "w", "stop"):
            raise ValueError(f"ResidualFollower needs the action [v, w, stop], got {inner.names}")
        self.scale, self.hold_below, self.acts_within = scale, hold_below, acts_within
        self.near_goal = True  # whether the policy decides now (see acts_within)
        self.action_layout = ActionLayout(("v", "w", "hold"))
        self.action_space = self.action_layout.space
        proposal = spaces.Box(-1.0, 1.0, (3,), np.float32)
        inner_space = env.observation_space
        assert isinstance(inner_space, spaces.Dict), inner_space
        self.observation_space = spaces.Dict({**inner_space.spaces, PROPOSAL: proposal})
        self.follower = FollowerAgent()
        self._proposal = np.zeros(3, np.float32)

    def reset(self, *, seed=None, options=None):
        """Reset the env and start the follower on the episode's route."""
        obs, info = self.env.reset(seed=seed, options=options)
        self.follower.begin(self.env)
        return self._propose(obs), info

    def step(self, action):
        """Drive the corrected action; ``info["declaration_held"]`` when the gate held one."""
        correction = np.asarray(action, dtype=np.float32).reshape(3)
        drive = np.clip(self._proposal[:2] + self.scale * correction[:2], -1.0, 1.0)
        declares = bool(self._proposal[2] > 0)
        held = declares and float(correction[2]) < self.hold_below
        if held:  # the follower heads for the same goal again
            self.follower.follower.goals_left = None
        stop = 1.0 if declares and not held else -1.0
        obs, reward, terminated, truncated, info = self.env.step(
            np.array([*drive, stop], np.float32)
        )
        info["declaration_held"] = held
        return self._propose(obs), reward, terminated, truncated, info

    def _propose(self, obs: dict) -> dict:
        self._proposal = np.asarray(self.follower.act(obs), dtype=np.float32)
        if self.acts_within is not None:
            offset = np.asarray(obs["goal"], float) - np.asarray(obs["pose"], float)[:2]
            self.near_goal = bool(np.hypot(*offset) <= self.acts_within)
        return {**obs, PROPOSAL: self._proposal.copy()}


def start_as_follower(policy, config: ResidualConfig) -> None:
    """Set an SB3 Gaussian policy's mean action to exactly 0 everywhere (the action net's
    weights and bias zeroed: the follower's own action) and its exploration to the config's
    standard deviations."""
    stds = [config.correction_std, config.correction_std, config.gate_std]
    with torch.no_grad():
        policy.action_net.weight.zero_()
        policy.action_net.bias.zero_()
        policy.log_std.copy_(torch.tensor([math.log(s) for s in stds]))
