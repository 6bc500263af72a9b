"""Agents by name, behind one interface, as the estimators are behind theirs.

An :class:`Agent` owns its policy stack: :meth:`~Agent.wrap` puts the wrappers it drives
through (its observation, its decision interval) over the pose-estimating env, and the
evaluation steps that stack, so an agent is evaluated exactly as it was trained. Names, read by
:func:`~stsf_gym.agents.resolve.resolve_agent` as every command reads them:

- ``follower``: the scripted path follower (:mod:`stsf_gym.agents.follower`); options override
  ``configs/agents/follower.yaml``; ``cautious-follower``: the follower that waits near a goal
  until its estimate is sure enough (:mod:`stsf_gym.agents.cautious_follower`);
  ``active-follower``: the cautious follower that turns or drives to see a map board where it
  would wait (:mod:`stsf_gym.agents.active_follower`);
- ``pretrained:<suite>/<algo>-<pose source>``: a shipped agent; a shipped agent's folder
  (``DIR/<suite>/<algo>-<pose source>``, shipped with ``--ship-to DIR``); a training folder;
  a ``.zip`` model saved by ``stsf-gym train``
  (:class:`~stsf_gym.agents.trained_agent.SB3Agent`). A name of several training seeds gives
  its first seed's agent from :func:`make_agent`, every seed's from :func:`make_agents`;
- ``package.module:Class``: an agent of your own, a class with this interface, built with the
  options as keyword arguments;
- any name given to :func:`register_agent`.

Three lines drive a shipped agent on the worlds it was made for::

    agent = make_agent("pretrained:sparse/dagger-mcl")
    env = agent.make_env()  # its suite's test worlds, its pose source, STOP, 0.5 s decisions
    obs, _ = env.reset(seed=0); agent.begin(env); obs, *_ = env.step(agent.act(obs))
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from typing import Protocol

import gymnasium as gym
import numpy as np

from stsf_gym.agents.follower_agent import FOLLOWER, FollowerAgent
from stsf_gym.validation import ConfigError, did_you_mean

CAUTIOUS_FOLLOWER = "cautious-follower"
ACTIVE_FOLLOWER = "active-follower"


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


#: The methods every agent has (:class:`Agent`'s).
AGENT_METHODS = tuple(m for m in vars(Agent) if not m.startswith("_"))


def _cautious_follower(**options) -> Agent:
    """``cautious-follower``, imported when asked for: the follower's module loads the
    simulator's config, which a replay (no simulator) never needs."""
    from stsf_gym.agents.cautious_follower import CautiousFollowerAgent

    return CautiousFollowerAgent(**options)


def _active_follower(**options) -> Agent:
    """``active-follower``, imported when asked for (as the cautious follower)."""
    from stsf_gym.agents.active_follower import ActiveFollowerAgent

    return ActiveFollowerAgent(**options)


#: Agents registered by name: name -> factory(**options).
AGENTS: dict[str, Callable[..., Agent]] = {
    FOLLOWER: FollowerAgent,
    CAUTIOUS_FOLLOWER: _cautious_follower,
    ACTIVE_FOLLOWER: _active_follower,
}


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
    """The agent called ``name`` (see the module's docstring) with ``options``; a name of
    several training seeds (a shipped agent, a training folder) gives its first seed's."""
    return make_agents(name, options)[0]


def check_agents(names: list[str]) -> None:
    """Make each agent of ``names`` once, so a missing model file or an unknown name fails
    before any work."""
    for name in names:
        make_agent(name)


def make_agents(name: str, options: dict | None = None) -> list[Agent]:
    """One agent per model ``name`` stands for (:func:`~stsf_gym.agents.resolve.resolve_agent`:
    each training seed of a shipped agent or a training folder), or the one agent by name."""
    options = options or {}
    if not isinstance(name, str) or not name.strip():
        raise ConfigError(f"an agent name may not be empty, got {name!r}")  # '' is the cwd
    if name in AGENTS:  # before the resolver: a folder of that name is not read as a run
        return [AGENTS[name](**options)]
    # imported when a name needs them: the resolver reads shipped agents' models (SB3, torch),
    # which a command driving the follower (each of its worker processes), or a replay, never
    # loads
    from stsf_gym.agents.resolve import resolve_agent
    from stsf_gym.agents.trained_agent import SB3Agent

    singles = resolve_agent(name)
    if singles[0].endswith(".zip"):
        if options:
            raise ConfigError(f"a saved model takes no agent options, got {sorted(options)}")
        return [SB3Agent(model) for model in singles]
    return [_named_agent(name, options)]


def check_agent(agent: object, name: str) -> Agent:
    """``agent`` (made by ``name``) if it has every method of :class:`Agent`, else a
    :class:`ConfigError` naming those it lacks."""
    missing = [m for m in AGENT_METHODS if not callable(getattr(agent, m, None))]
    if missing:
        raise ConfigError(
            f"agent {name!r} made a {type(agent).__name__}, which is not an agent: it lacks "
            f"{', '.join(missing)} (stsf_gym.agents.registry.Agent)"
        )
    return agent  # type: ignore[return-value]


def _named_agent(name: str, options: dict) -> Agent:
    """``package.module:Class`` with ``options``."""
    module, sep, attr = name.partition(":")
    if sep and module and attr:
        try:
            factory = getattr(importlib.import_module(module), attr)
        except (ImportError, AttributeError) as err:
            raise ConfigError(f"agent {name!r} not found: {err}") from None
        if not callable(factory):
            raise ConfigError(f"agent {name!r} is a {type(factory).__name__}, not an agent class")
        _check_call(factory, name, options)
        return check_agent(factory(**options), name)
    raise ConfigError(
        f"unknown agent {name!r}{did_you_mean(name, AGENTS)}; known: {', '.join(AGENTS)}, "
        "a shipped agent "
        "(pretrained:SUITE/ALGO-SOURCE, `stsf-gym agents`), a training folder, a saved model "
        "(.zip) or package.module:Class"
    )


def _check_call(factory: Callable, name: str, options: dict) -> None:
    """A :class:`ConfigError` when ``factory`` cannot be called with ``options`` (``json:loads``
    needs an argument; a protocol, such as :class:`Agent`, makes no object), before it is
    called: a ``TypeError`` from inside a factory that could be called stays the bug it is."""
    if getattr(factory, "_is_protocol", False):
        raise ConfigError(f"agent {name!r} is a protocol (an interface), not an agent class")
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):  # a builtin without a signature: called as it is
        return
    try:
        signature.bind(**options)
    except TypeError as err:
        given = f"the options {sorted(options)}" if options else "no options"
        raise ConfigError(f"agent {name!r} cannot be made with {given}: {err}") from None
