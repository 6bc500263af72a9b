"""Hyper-parameters of the SB3 agents: rl-zoo style YAML, one file per algorithm.

``configs/agents/<algo>.yaml`` holds a ``default`` section and optional sections named by
registered env id (``stsf_gym/Corridor-Truth-v0``, ...), merged over it. A section mixes
training keys (:class:`TrainingConfig`) with the algorithm's own keyword arguments
(``learning_rate``, ``n_steps``, ``gamma``, ...), checked against its signature and, for
numbers, against their mathematical range (:data:`ALGO_RANGES`). Unknown sections, unknown keys
and values of the wrong type or out of range raise :class:`ConfigError` naming the key and
where it was set: the file and section, or ``--set``.
"""

from __future__ import annotations

import dataclasses
import difflib
import importlib
import inspect
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import gymnasium as gym

import stsf_gym  # noqa: F401 - registers the env ids that name sections
from stsf_gym.agents.decision_interval import DEFAULT_DECISION_STEPS
from stsf_gym.agents.demonstrations.dagger import DemonstrationConfig, demonstration_config
from stsf_gym.agents.observation import ObservationConfig, observation_config
from stsf_gym.agents.rl.residual import ResidualConfig
from stsf_gym.config_files import deep_merge, shown
from stsf_gym.envs.config import CONFIG_DIR, build, overrides_to_tree, read_yaml
from stsf_gym.validation import (
    ConfigError,
    Count,
    KeySources,
    NonNegative,
    Positive,
    Range,
    check_number,
    require,
)

#: Supported algorithms: name -> "module:class" of the stable-baselines3 learner.
ALGORITHMS: dict[str, str] = {"ppo": "stable_baselines3:PPO", "sac": "stable_baselines3:SAC"}
#: What ran, as ``algo`` records it, -> its learner: cloning and DAgger rounds without reward
#: (``dagger``), then PPO on the env's reward (``dagger+ppo``); ``ppo`` and ``sac`` on reward alone.
METHODS: dict[str, str] = {
    "dagger": "ppo", "dagger+ppo": "ppo", "ppo": "ppo", "sac": "sac", "residual+ppo": "ppo",
}  # fmt: skip
#: The residual learner (agents/rl/residual.py): PPO on a correction of the follower.
RESIDUAL = "residual+ppo"
#: Constructor arguments the trainer sets itself (or that name classes, not values).
RESERVED = {
    "self", "policy", "env", "policy_kwargs", "tensorboard_log", "verbose", "seed", "device",
    "_init_setup_model", "action_noise", "rollout_buffer_class", "replay_buffer_class",
}  # fmt: skip
SUITES = "suites"  # the section for training on a benchmark suite (declared arrival)
RL_READY = "rl-ready"  # over ``suites``: the RL-ready ids' learner (agents/rl/ready.py)
ACTIVATIONS = {"tanh": "Tanh", "relu": "ReLU", "elu": "ELU", "leaky_relu": "LeakyReLU"}
#: Where ``load_hyperparams``'s ``overrides`` come from, as errors name it.
OVERRIDES = "--set"
#: The allowed values of the algorithms' numeric arguments: out of them SB3 trains on NaNs or
#: fails only after the run's files are written.
ALGO_RANGES: dict[str, Range] = {
    "learning_rate": Range(gt=0),
    "gamma": Range(ge=0, le=1),  # a discount
    "gae_lambda": Range(ge=0, le=1),
    "clip_range": Range(gt=0),
    "ent_coef": Range(ge=0),
    "vf_coef": Range(ge=0),
    "max_grad_norm": Range(gt=0),
    "n_steps": Range(ge=2),  # SB3 normalises advantages over a rollout: more than one step
    "batch_size": Range(ge=2),  # ... and over a minibatch
    "n_epochs": Range(ge=1),
    "tau": Range(gt=0, le=1),  # a soft update's share
    "buffer_size": Range(ge=1),
    "learning_starts": Range(ge=0),
    "train_freq": Range(ge=1),
    "gradient_steps": Range(ge=-1),  # -1: as many as the env steps collected
    "target_update_interval": Range(ge=1),
}


@dataclass(frozen=True)
class TrainingConfig:
    """The training keys of a section (everything else goes to the algorithm)."""

    n_envs: Count
    n_timesteps: Annotated[int, Range(ge=0)]
    policy: str
    eval_freq: Count  # env steps (summed over the envs) between evaluations
    n_eval_episodes: Count
    checkpoint_freq: Count  # env steps (summed over the envs) between checkpoints
    policy_kwargs: dict = field(default_factory=dict)
    env: dict = field(default_factory=dict)  # env overrides, as gym.make keyword sections
    observation: dict = field(default_factory=dict)  # stsf_gym.agents.observation.ObservationConfig
    decision_steps: Count = DEFAULT_DECISION_STEPS  # control steps per decision
    train_env: dict = field(default_factory=dict)  # over env, for the training envs only (legs)
    demonstrations: dict = field(default_factory=dict)  # agents/demonstrations/dagger.py
    finetune: dict = field(default_factory=dict)  # FinetuneConfig: reward after demonstrations
    #: --algo residual+ppo: the ResidualConfig bounds, and ``observation`` and ``finetune``
    #: settings that replace the section's for the residual learner
    residual: dict = field(default_factory=dict)
    #: Chance that a fresh policy's STOP entry declares at a decision (plain RL only; see
    #: agents/training/stop_prior.py): 0.5 would end most legs within a few decisions.
    initial_stop_probability: Annotated[float, Range(gt=0, lt=1)] = 0.0025

    def __post_init__(self) -> None:
        dicts = (
            "policy_kwargs", "env", "observation", "train_env", "demonstrations", "finetune",
            "residual",
        )  # fmt: skip
        for name in dicts:
            value = getattr(self, name)
            require(isinstance(value, dict), name, f"must be a mapping, got {value!r}")


@dataclass(frozen=True)
class FinetuneConfig:
    """Learning from reward after the demonstrations (``finetune:``), on the clone's weights:
    ``timesteps`` of PPO (decisions summed over the envs; ``--timesteps`` overrides) whose
    first ``value_warmup_steps`` train the value function alone, the actor frozen (a critic
    fresh from cloning would otherwise steer the first updates with noise), at
    ``learning_rate`` (None: the algorithm's), each update followed by a pull of the mean
    action toward the clone's (``clone_kl_coef``, agents/training/finetune.py), and each
    action entry's standard deviation at least ``exploration_std`` from the start (None: the
    clone's)."""

    timesteps: Annotated[int, Range(ge=0)] = 0
    value_warmup_steps: Annotated[int, Range(ge=0)] = 0
    learning_rate: Positive | None = None
    clone_kl_coef: NonNegative = 0.0
    exploration_std: Annotated[float, Range(gt=0, le=1)] | None = None


@dataclass(frozen=True)
class Hyperparams:
    """An algorithm's hyper-parameters for one env id: the ``default`` section with the id's
    section merged over it, split into training settings and the algorithm's own arguments;
    the nested settings typed (checked once, here), with the layer that set each key.
    """

    algo: str
    section: str  # the env id section merged over ``default`` ("default" if none)
    training: TrainingConfig
    algo_kwargs: dict  # keyword arguments of the algorithm's constructor
    observation: ObservationConfig
    demonstrations: DemonstrationConfig
    finetune: FinetuneConfig
    residual: ResidualConfig | None  # --algo residual+ppo only
    sources: KeySources = field(compare=False, repr=False)
    default_source: str = ""  # the file and section named when no layer set a key

    def error(self, message: str, key: str) -> ConfigError:
        """A ConfigError about ``key``, naming the layer (file and section, or --set) it came
        from."""
        return ConfigError(message, key, self.sources.file_of(key) or self.default_source)


def update_size(hp: Hyperparams, n_envs: int) -> tuple[int, str]:
    """Env steps (summed over the envs) between two points where a run can stop, and what
    makes them: PPO stops only after a whole rollout (``n_steps`` per env), SAC after
    ``train_freq`` steps per env (an integer: the hyper-parameter check takes no episodes)."""
    from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm

    cls = algorithm_class(hp.algo)
    defaults = inspect.signature(cls.__init__).parameters
    key = "n_steps" if issubclass(cls, OnPolicyAlgorithm) else "train_freq"
    return int(hp.algo_kwargs.get(key, defaults[key].default)) * n_envs, f"{key} x n_envs"


def check_timesteps(hp: Hyperparams, n_envs: int, total: int) -> None:
    """``total`` must be a whole number of :func:`update_size`: the run then ends at exactly
    ``total`` steps, resumed or not."""
    size, what = update_size(hp, n_envs)
    if total % size:
        below, above = total // size * size, (total // size + 1) * size
        raise ConfigError(
            f"timesteps {total} is not a multiple of {what} = {size}: the run would end at "
            f"{above}; ask for {f'{below} or ' if below else ''}{above}"
        )


def learner_of(algo: str) -> str:
    """The learner (``ppo`` or ``sac``) of ``algo`` (a method of :data:`METHODS`)."""
    if algo not in METHODS:
        raise ConfigError(f"unknown algorithm {algo!r}; known: {', '.join(METHODS)}")
    return METHODS[algo]


def algorithm_class(algo: str) -> type:
    """The stable-baselines3 class of ``algo`` (any of :data:`METHODS`); ConfigError otherwise."""
    module, _, name = ALGORITHMS[learner_of(algo)].partition(":")
    return getattr(importlib.import_module(module), name)


def load_hyperparams(
    algo: str,
    env_id: str | None,
    path: str | Path | None = None,
    overrides: dict[str, Any] | None = None,
    suite: bool = False,
    rl_ready: bool = False,
) -> Hyperparams:
    """The ``default`` section of ``path`` (``configs/agents/<algo>.yaml``), with the ``suites``
    section when training on a suite, the ``rl-ready`` section for the RL-ready ids, the
    ``env_id`` section and then ``overrides`` (flat ``key.sub=value`` or nested) over it.
    ``algo``'s learner names the file."""
    cls = algorithm_class(algo)
    path = Path(path or CONFIG_DIR / "agents" / f"{learner_of(algo)}.yaml")
    data = read_yaml(path)
    for section, body in data.items():
        if section not in ("default", SUITES, RL_READY) and section not in gym.registry:
            close = difflib.get_close_matches(str(section), list(gym.registry), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ConfigError(
                f"{path}: unknown section {section!r}{hint}; use 'default', 'suites', "
                "'rl-ready' or a registered env id such as 'stsf_gym/Corridor-Truth-v0'"
            )
        if not isinstance(body, dict):
            raise ConfigError(f"{path}: section {section!r} must be a mapping, got {body!r}")
    chosen = env_id if env_id in data else "default"
    sections = [
        "default",
        *([SUITES] if suite or rl_ready else []),
        *([RL_READY] if rl_ready else []),
        *([env_id] if env_id else []),
    ]
    layers = [(f"{shown(path)} [{name}]", data.get(name, {})) for name in sections]
    layers.append((OVERRIDES, overrides_to_tree(overrides or {})))
    merged: dict = {}
    sources = KeySources()
    for source, layer in layers:
        if algo == RESIDUAL:  # each layer's residual settings over its own, layer by layer
            layer = residual_section(layer)
        merged = deep_merge(merged, layer)
        sources.record(layer, source)
    training_keys = {f.name for f in dataclasses.fields(TrainingConfig)}
    try:
        training = build(
            TrainingConfig, {k: v for k, v in merged.items() if k in training_keys}, ""
        )
        algo_kwargs = {k: v for k, v in merged.items() if k not in training_keys}
        _check_algo_kwargs(cls, algo_kwargs)
        _check_policy_kwargs(training.policy_kwargs)
        typed = (
            observation_config(training.observation),
            demonstration_config(training.demonstrations),
            build(FinetuneConfig, training.finetune, "finetune"),
            build(ResidualConfig, training.residual, "residual") if algo == RESIDUAL else None,
        )
    except ConfigError as err:  # named by the layer that set the key (the file if none did)
        where = sources.file_of(err.key) or f"{shown(path)} [{chosen}]"
        raise ConfigError(err.message, err.key, where) from None
    return Hyperparams(
        algo, chosen, training, algo_kwargs, *typed, sources, f"{shown(path)} [{chosen}]"
    )


def residual_section(layer: dict) -> dict:
    """A layer as the residual learner reads it: its ``residual.observation`` and
    ``residual.finetune`` over its own, its ``residual.train_env`` (where given) in place of
    its own (``{}``: the task as evaluated), no demonstrations (the learner starts as the
    follower), and ``residual`` keeping only the bounds (:class:`ResidualConfig`)."""
    residual = dict(layer.get("residual") or {})
    layer = {**layer, "demonstrations": {"expert_episodes": 0}}
    for key in ("observation", "finetune"):
        layer[key] = deep_merge(layer.get(key) or {}, residual.pop(key, None) or {})
    if "train_env" in residual:
        layer["train_env"] = residual.pop("train_env") or {}
    return {**layer, "residual": residual}


def _check_algo_kwargs(cls: type, kwargs: dict) -> None:
    """Names from ``cls.__init__``; types from its defaults (a ``None`` default takes any);
    every number finite and within :data:`ALGO_RANGES`."""
    parameters = inspect.signature(cls.__init__).parameters
    allowed = [name for name in parameters if name not in RESERVED]
    for key, value in kwargs.items():
        if key not in allowed:
            close = difflib.get_close_matches(key, [*allowed, "n_envs", "n_timesteps"], n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ConfigError(f"unknown hyper-parameter {key!r} for {cls.__name__}{hint}", key)
        default = parameters[key].default
        if default is None:
            continue
        if isinstance(default, bool):
            ok = isinstance(value, bool)
        elif isinstance(default, int | float):
            ok = isinstance(value, int | float) and not isinstance(value, bool)
            ok = ok and (not isinstance(default, int) or float(value).is_integer())
        else:  # a string default such as ent_coef: "auto" also takes a number
            ok = isinstance(value, str | int | float) and not isinstance(value, bool)
        if not ok:
            raise ConfigError(f"{key} must be like {default!r}, got {value!r}", key)
        if isinstance(value, int | float) and not isinstance(value, bool):
            integer = isinstance(default, int) and not isinstance(default, bool)
            kwargs[key] = check_number(value, key, ALGO_RANGES.get(key, Range()), integer=integer)


def _check_policy_kwargs(policy_kwargs: dict) -> None:
    activation = policy_kwargs.get("activation_fn")
    if activation is not None and activation not in ACTIVATIONS:
        raise ConfigError(
            f"policy_kwargs.activation_fn must be one of {list(ACTIVATIONS)}, got {activation!r}",
            "policy_kwargs.activation_fn",
        )


def policy_kwargs_for_sb3(policy_kwargs: dict) -> dict:
    """``policy_kwargs`` with the activation's name replaced by the ``torch.nn`` class."""
    import torch.nn

    kwargs = dict(policy_kwargs)
    if "activation_fn" in kwargs:
        kwargs["activation_fn"] = getattr(torch.nn, ACTIVATIONS[kwargs["activation_fn"]])
    return kwargs
