"""Agents by name, behind one interface, as the estimators are behind theirs.

An :class:`Agent` owns its policy stack: :meth:`~Agent.wrap` puts the wrappers it drives
through (its observation, its decision interval) over the pose-estimating env, and the
evaluation steps that stack, so an agent is evaluated exactly as it was trained. Names:

- ``follower``: the scripted path follower (:mod:`stsf_gym.agents.follower`); options override
  ``configs/agents/follower.yaml``;
- a path ending in ``.zip``: a model saved by ``stsf-gym train`` (:class:`SB3Agent`);
- ``package.module:Class``: an agent of your own, a class with this interface, built with the
  options as keyword arguments;
- any name given to :func:`register_agent`.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Protocol

import gymnasium as gym
import numpy as np

from stsf_gym.validation import ConfigError

FOLLOWER = "follower"


class Agent(Protocol):
    """What an evaluation needs of an agent."""

    def wrap(self, env: gym.Env) -> gym.Env:
        """The env the agent drives: ``env`` under the agent's own wrappers (or ``env``)."""

    def begin(self, env: gym.Env) -> None:
        """Called after each reset of :meth:`wrap`'s env (the world may be new)."""

    def act(self, obs) -> np.ndarray:
        """The action for ``obs``, an observation of :meth:`wrap`'s env."""

    def env_overrides(self) -> dict:
        """Env settings the agent needs over an evaluation's (the action entries it drives)."""

    def trained_on(self) -> dict | None:
        """What a learnt agent was trained on (``algo``, ``estimator``, ``world``, ...); None
        for an agent that drives on whatever pose source it is given."""

    def config(self) -> dict:
        """The agent's resolved settings, for the results' provenance."""

    def label(self) -> str:
        """A short name for file names and tables."""


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
        """A follower of this episode's path and goals."""
        from stsf_gym.agents.follower import PathFollower

        self.follower = PathFollower.for_env(env, **self.options)

    def act(self, obs) -> np.ndarray:
        """Pure pursuit on ``obs["pose"]``, bent by the sonar."""
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


class SB3Agent:
    """A model saved by ``stsf-gym train``, behind the policy stack it was trained with
    (:func:`~stsf_gym.agents.policy_stack.policy_stack`); its actions deterministic."""

    def __init__(self, path: str) -> None:
        from stsf_gym.agents.sb3_agent import check_weights, model_digest, model_metadata

        self.path = check_weights(path)  # a missing file or corrupt weights: refused here
        self.meta, self.digest = model_metadata(self.path), model_digest(self.path)
        self.model = None

    def wrap(self, env: gym.Env) -> gym.Env:
        """The policy stack of the model's record over ``env``; shapes checked."""
        from stsf_gym.agents.policy_stack import policy_stack
        from stsf_gym.agents.sb3_agent import load_model

        stack = policy_stack(env, self.meta.get("observation"), self.meta.get("decision_steps", 1))
        self.model = load_model(self.path)
        for space in ("observation_space", "action_space"):
            theirs, ours = getattr(self.model, space), getattr(stack, space)
            if theirs.shape != ours.shape:
                raise ConfigError(
                    f"{self.path} expects an {space.split('_')[0]} of shape {theirs.shape}, "
                    f"this env's is {ours.shape}"
                )
        return stack

    def begin(self, env: gym.Env) -> None:
        """Nothing: the policy keeps no state between steps."""
        pass

    def act(self, obs) -> np.ndarray:
        """The model's deterministic action."""
        action, _ = self.model.predict(obs, deterministic=True)
        return action

    def env_overrides(self) -> dict:
        """The STOP entry, if the model was trained with one."""
        stop = self.meta.get("env", {}).get("task", {}).get("stop_action", False)
        return {"task": {"stop_action": True}} if stop else {}

    def trained_on(self) -> dict:
        """Algorithm, pose source, world, timesteps and digest of the model."""
        from stsf_gym.agents.sb3_agent import training_record

        return training_record(self.path)

    def config(self) -> dict:
        """The model's path and content digest."""
        return {"model": str(self.path), "digest": self.digest}

    def label(self) -> str:
        """The model file's stem and digest."""
        return f"{self.path.stem}-{self.digest}"


#: Agents registered by name: name -> factory(**options).
AGENTS: dict[str, Callable[..., Agent]] = {FOLLOWER: FollowerAgent}


def register_agent(name: str, factory: Callable[..., Agent]) -> None:
    """Make ``name`` an agent wherever one is named (``--agents``, ``EpisodeSpec.agent``)."""
    if ":" in name or name.endswith(".zip"):
        raise ValueError(f"agent names may not contain ':' or end in .zip, got {name!r}")
    AGENTS[name] = factory


def trained_on(name: str) -> dict | None:
    """What agent ``name`` was trained on (:meth:`Agent.trained_on`; None if it is not learnt
    or does not say)."""
    agent = make_agent(name)
    return getattr(agent, "trained_on", lambda: None)()


def make_agent(name: str, options: dict | None = None) -> Agent:
    """The agent called ``name`` (see the module's docstring) with ``options``."""
    options = options or {}
    if name in AGENTS:
        return AGENTS[name](**options)
    if name.endswith(".zip"):
        if options:
            raise ConfigError(f"a saved model takes no agent options, got {sorted(options)}")
        return SB3Agent(name)
    module, sep, attr = name.partition(":")
    if sep and module and attr:
        try:
            cls = getattr(importlib.import_module(module), attr)
        except (ImportError, AttributeError) as err:
            raise ConfigError(f"agent {name!r} not found: {err}") from None
        return cls(**options)
    raise ConfigError(
        f"unknown agent {name!r}; known: {', '.join(AGENTS)}, a saved model (.zip) or "
        "package.module:Class"
    )
