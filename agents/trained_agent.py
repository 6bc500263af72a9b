"""A model saved by ``stsf-gym train`` as an agent: the env it was trained for, the policy stack it
was trained behind, and its settings checked against any env it is given.

A saved model carries what it was trained on (``stsf_meta``, :mod:`~stsf_gym.agents.model_files`):
the world or suite, the pose source, the env settings (its STOP entry among them), the policy's
observation settings and its decision interval. :func:`wrap_for_model` puts an env under that
stack, and refuses an env whose settings differ from the model's (another STOP layout, another
control period, a policy observation or decision interval of other settings already wrapped),
since the same 37 numbers in another meaning would run silently and wrong.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

from stsf_gym.validation import ConfigError

TEST_WORLDS = "generated:test"  # a suite's held-out worlds, where its agents are compared


def wrap_for_model(env: gym.Env, model: str | Path) -> gym.Env:
    """``env`` (a pose-estimating env: ``obs["pose"]`` and ``obs["pose_cov"]``) as the saved
    ``model`` sees and drives it: its :class:`~stsf_gym.agents.observation.PolicyObservation`
    and :class:`~stsf_gym.agents.decision_interval.DecisionInterval` with the settings saved in
    it. ``env`` already under the model's own stack is returned as it is. ConfigError when a
    setting of ``env`` differs from the model's (see :func:`check_env`)."""
    from stsf_gym.agents.model_files import model_metadata

    return stack_for(env, model_metadata(model), model)


def stack_for(env: gym.Env, meta: dict, model: str | Path) -> gym.Env:
    """:func:`wrap_for_model` with the model's metadata ``meta`` given (``model`` names it)."""
    from stsf_gym.agents.decision_interval import DecisionInterval
    from stsf_gym.agents.observation import PolicyObservation, observation_config
    from stsf_gym.agents.policy_stack import policy_stack

    check_env(env, meta, model)
    observation, steps = observation_config(meta.get("observation")), meta["decision_steps"]
    wrapped = _wrapper(env, PolicyObservation)
    if wrapped is None:
        return policy_stack(env, meta.get("observation"), steps, meta.get("residual"))
    if wrapped.config != observation:
        raise ConfigError(
            f"{model} was trained on the policy observation {observation}; this env is "
            f"wrapped in one of {wrapped.config}"
        )
    interval = _wrapper(env, DecisionInterval)
    held = 1 if interval is None else interval.steps
    if held != steps:
        raise ConfigError(
            f"{model} decides every {steps} control steps (decision_steps); this env's "
            f"DecisionInterval holds {held}"
        )
    return env


def check_env(env: gym.Env, meta: dict, model: str | Path) -> None:
    """ConfigError naming the setting where ``env`` differs from what ``model`` (its metadata
    ``meta``) was trained with: the pose estimate in the observation, the STOP entry
    (``task.stop_action``), the control period (``sim.control_dt``)."""
    from stsf_gym.envs.config import load_config

    outer = env.observation_space
    if isinstance(outer, gym.spaces.Dict) and not {"pose", "pose_cov"} <= set(outer.spaces):
        raise ConfigError(
            f"{model} drives on a pose estimate: wrap the env in PoseEstimateWrapper (or make "
            f"an estimating id, stsf_gym/Suite-<Suite>-<Source>-v0); its observation has "
            f"{sorted(outer.spaces)}"
        )
    if "env" not in meta:  # no env settings recorded: nothing more to compare
        return
    stop = bool(meta["env"].get("task", {}).get("stop_action", False))
    has_stop = "stop" in env.get_wrapper_attr("action_layout")
    if stop != has_stop:
        fix = "task__stop_action=True" if stop else "task__stop_action=False"
        raise ConfigError(
            f"{model} was trained {'with' if stop else 'without'} the STOP action entry "
            f"(task.stop_action: {str(stop).lower()}); this env has "
            f"{'it' if has_stop else 'none'}: make the env with {fix}"
        )
    trained_dt = meta["env"].get("sim", {}).get("control_dt")
    trained_dt = load_config().sim.control_dt if trained_dt is None else trained_dt
    if not np.isclose(env.unwrapped.dt, trained_dt):
        raise ConfigError(
            f"{model} was trained at a control period of {trained_dt:g} s (sim.control_dt); "
            f"this env steps {env.unwrapped.dt:g} s"
        )


def _wrapper(env: gym.Env, kind: type) -> gym.Wrapper | None:
    """The outermost wrapper of ``kind`` around ``env`` (None if there is none)."""
    while isinstance(env, gym.Wrapper):
        if isinstance(env, kind):
            return env
        env = env.env
    return None


class SB3Agent:
    """A model saved by ``stsf-gym train``, behind the policy stack it was trained with; its
    actions deterministic. :meth:`make_env` builds the env it was trained for."""

    def __init__(self, path: str) -> None:
        from stsf_gym.agents.model_files import check_weights, model_digest, model_metadata

        self.path = check_weights(path)  # a missing file or corrupt weights: refused here
        self.meta, self.digest = model_metadata(self.path), model_digest(self.path)
        self.model = None

    def make_env(self, pose_source: str | None = None, world: str | None = None, **env) -> gym.Env:
        """The env this model was trained for, under its whole policy stack: its suite's test
        worlds (or the world it was trained on) on its own pose source, with the env settings
        saved in it (STOP entry, task, sensors); ``pose_source``, ``world`` and ``env``
        settings (nested mappings or ``section__key`` overrides) replace them."""
        from stsf_gym.config_files import deep_merge, overrides_to_tree
        from stsf_gym.episode_env import make_episode_env

        world = world or (TEST_WORLDS if self.meta.get("suite") else self.meta["world"])
        settings = deep_merge(self.meta.get("env", {}), overrides_to_tree(env))
        estimating = make_episode_env(world, pose_source or self.meta["estimator"], settings)
        return self.wrap(estimating)

    def wrap(self, env: gym.Env) -> gym.Env:
        """``env`` under the model's policy stack (:func:`stack_for`); shapes checked."""
        from stsf_gym.agents.model_files import load_model

        stack = stack_for(env, self.meta, self.path)
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
        """The task the model declares arrival in, if it was trained with the STOP entry: the
        entry and the declare protocol it needs (any world's route is then its goals)."""
        stop = self.meta.get("env", {}).get("task", {}).get("stop_action", False)
        return {"task": {"protocol": "declare", "stop_action": True}} if stop else {}

    def trained_on(self) -> dict:
        """Algorithm, pose source, world, timesteps and digest of the model."""
        from stsf_gym.agents.model_files import training_record

        return training_record(self.path)

    def config(self) -> dict:
        """The model's path and content digest."""
        return {"model": str(self.path), "digest": self.digest}

    def label(self) -> str:
        """The model file's stem and digest."""
        return f"{self.path.stem}-{self.digest}"
