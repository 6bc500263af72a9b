"""The scripted path follower as an agent (:mod:`stsf_gym.agents.registry`'s ``follower``)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

FOLLOWER = "follower"


class FollowerAgent:
    """The scripted path follower on the pose estimate: a decision every control step, or
    every ``decision_steps`` (:class:`~stsf_gym.agents.decision_interval.DecisionInterval`, as
    a learnt policy decides); other options override ``configs/agents/follower.yaml``."""

    def __init__(self, decision_steps: int = 1, **options) -> None:
        from stsf_gym.agents.follower import load_follower_config

        self.decision_steps, self.options = decision_steps, options
        self.settings = load_follower_config(**options)  # bad options fail here, early
        self.follower = None

    def wrap(self, env: gym.Env) -> gym.Env:
        """The env itself, or held decisions with ``decision_steps`` above 1."""
        from stsf_gym.agents.decision_interval import DecisionInterval

        return env if self.decision_steps == 1 else DecisionInterval(env, self.decision_steps)

    def begin(self, env: gym.Env) -> None:
        """A follower of this episode's path."""
        from stsf_gym.agents.follower import PathFollower

        self.follower = PathFollower.for_env(env, **self.options)

    def act(self, obs) -> np.ndarray:
        """Pure pursuit on ``obs["pose"]``, bent by the sonar, to the goal the observation
        gives (``obs["goal_arc"]`` while ``obs["goals_left"]``)."""
        self.follower.see_goal(float(obs["goal_arc"][0]), int(obs["goals_left"][0]))
        return self.follower.act(obs["pose"], obs["sonar"])

    def env_overrides(self) -> dict:
        """None needed."""
        return {}  # any action layout: it stops by standing still, or by STOP if there is one

    def trained_on(self) -> dict | None:
        """Nothing: the follower is scripted."""
        return None

    def config(self) -> dict:
        """The follower's resolved settings."""
        from dataclasses import asdict

        interval = {} if self.decision_steps == 1 else {"decision_steps": self.decision_steps}
        return {FOLLOWER: asdict(self.settings), **interval}

    def label(self) -> str:
        """``follower``, or ``follower-k<steps>`` with a decision interval."""
        return FOLLOWER if self.decision_steps == 1 else f"{FOLLOWER}-k{self.decision_steps}"
