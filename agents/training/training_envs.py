"""The envs of a training run: the same env as every evaluated agent (``make_episode_env``),
behind the policy's stack (:func:`~stsf_gym.agents.policy_stack.policy_stack`), monitored; in
worker processes when there are several; and the deterministic evaluation on held-out worlds.
"""

from __future__ import annotations

import signal
from functools import partial
from pathlib import Path

import gymnasium as gym
import numpy as np
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv

import stsf_gym
from stsf_gym.agents.demonstrations.expert import ExpertLabel
from stsf_gym.agents.observation import ObservationConfig, PolicyObservation
from stsf_gym.agents.policy_stack import policy_stack
from stsf_gym.agents.training.worker_envs import FailFastSubprocVecEnv
from stsf_gym.envs.generated_env import generated_label, parse_world
from stsf_gym.episode_env import make_episode_env
from stsf_gym.results.code_identity import loaded_modules, note_worker_modules

EVAL_SEED_OFFSET = 10_000  # the evaluation env's seed is the training seed plus this


def env_id_for(world: str, estimator: str, suite: str | None = None) -> str | None:
    """The registered id of ``world`` (or of ``suite``) driven on ``estimator`` (None if not
    registered)."""
    base = next((i for i, w in stsf_gym.ENV_WORLDS.items() if w == world), None)
    if parse_world(world) is not None:
        base = stsf_gym.suite_id(suite) if suite else stsf_gym.GENERATED_ID
    suffix = next((s for s, e in stsf_gym.ESTIMATOR_IDS.items() if e == estimator), None)
    return base.replace("-v0", f"-{suffix}-v0") if base and suffix else None


def evaluation_world(world: str) -> str:
    """Where training evaluates: generated worlds on the ``val`` split (held out from training
    and from the benchmark's ``test``), a fixed world on itself with other seeds."""
    return generated_label("val") if parse_world(world) is not None else world


def check_training_env(world: str, estimator: str, env: dict, seed: int) -> None:
    """Make and reset the first training env here, so a setting only an env can check (a start
    range wider than the corridor, say) fails before any file is written or worker started."""
    probe = make_episode_env(world, estimator, env, {})
    try:
        probe.reset(seed=seed)
    finally:
        probe.close()


def make_training_env(
    world: str,
    estimator: str,
    env: dict,
    observation: ObservationConfig,
    decision_steps: int,
    monitor_file: str,
    in_worker: bool,
    expert: str | None = None,
    residual: dict | None = None,
) -> gym.Env:
    """One monitored env behind the policy's stack (built inside a worker process); with
    ``expert`` (the teacher's pose: ``truth`` or ``estimate``) the follower labels every state
    (:class:`ExpertLabel`, demonstrations); with
    ``residual`` the policy corrects the follower (:class:`~stsf_gym.agents.rl.residual.
    ResidualFollower`'s bounds)."""
    if in_worker:  # Ctrl-C is the parent's to handle: it saves a checkpoint, then closes us
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    estimating = make_episode_env(world, estimator, env, {})
    labelled = estimating
    if expert:  # the expert labels every control step in the policy's features
        features = PolicyObservation(estimating, observation)
        labelled = ExpertLabel(estimating, features, expert)
    policy_env = policy_stack(labelled, observation, decision_steps, residual)
    fresh = not Path(f"{monitor_file}.{Monitor.EXT}").is_file()
    monitored = Monitor(
        policy_env, monitor_file, info_keywords=("is_success",), override_existing=fresh
    )
    monitored.loaded_modules = loaded_modules  # what note_workers_code asks the env's process
    return monitored


def note_workers_code(venv: VecEnv) -> None:
    """Count the package modules the env processes of ``venv`` loaded as this run's code."""
    for modules in venv.env_method("loaded_modules"):
        note_worker_modules(modules)


def make_vec_env(n_envs: int, out: Path, tag: str, **spec) -> VecEnv:
    """``n_envs`` envs: in forkserver worker processes when more than one."""
    in_workers = n_envs > 1
    factories = [
        partial(
            make_training_env,
            monitor_file=str(out / "monitor" / f"{tag}{rank}"),
            in_worker=in_workers,
            **spec,
        )
        for rank in range(n_envs)
    ]
    return FailFastSubprocVecEnv(factories, "forkserver") if in_workers else DummyVecEnv(factories)


def val_outcomes(model, eval_env: VecEnv, episodes: int, seed: int) -> tuple[list[bool], list]:
    """Whether ``model``'s deterministic policy finishes each of ``episodes`` episodes of the
    evaluation env (reseeded: the same worlds each time) with success, and their returns."""
    from stable_baselines3.common.evaluation import evaluate_policy

    eval_env.seed(seed)
    successes: list[bool] = []

    def record(local: dict, _: dict) -> None:
        if local["done"]:
            successes.append(bool(local["info"].get("is_success", False)))

    returns, _ = evaluate_policy(
        model, eval_env, episodes, deterministic=True, callback=record, warn=False,
        return_episode_rewards=True,
    )  # fmt: skip
    return successes, [float(r) for r in np.asarray(returns)]
