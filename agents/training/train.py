"""``stsf-gym train``: a PPO or SAC agent driving on one pose source, resumable.

The agent runs in the same env as every evaluated agent (``make_episode_env``: the pan camera
pointed by :class:`PoseEstimateWrapper`), with :class:`PolicyObservation` on top and
``Monitor`` outside. ``OUT`` receives ``checkpoints/``, ``tb/`` (TensorBoard), ``monitor/``,
``eval/`` and ``best/`` (the best evaluated model), ``episodes.csv``, ``eval.csv``,
``learning_curve.png``, ``model.zip`` and ``train.json``. With ``suite`` the agent trains on a
benchmark suite's train worlds under its task and is evaluated (best model chosen) on the
suite's ``val`` worlds, never on the benchmark's ``test`` ones. Rerunning with the same ``OUT``
continues from the newest checkpoint (PPO checkpoints after every update, SAC every
``checkpoint_freq`` steps and on Ctrl-C) and ends at exactly the timesteps asked for, which must
be a whole number of updates (:func:`~stsf_gym.agents.training.hyperparams.check_timesteps`). A
checkpoint made by other code or another resolved configuration (its
:func:`~stsf_gym.results.provenance.fingerprint` differs) is not resumed: the run says so, moves
the old checkpoints to ``stale-checkpoints/`` and starts afresh. ``train.json`` and every model
file carry the run's provenance.
"""

from __future__ import annotations

import io
import json
import os
import re
import signal
import sys
import time
import warnings
from dataclasses import asdict
from functools import partial
from pathlib import Path

import gymnasium as gym
from stable_baselines3.common.callbacks import BaseCallback, CallbackList
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv

import stsf_gym
from stsf_gym.agents.demonstrations.dagger import demonstration_config, run_demonstrations
from stsf_gym.agents.demonstrations.expert import ExpertLabel
from stsf_gym.agents.observation import observation_config
from stsf_gym.agents.policy_stack import policy_stack
from stsf_gym.agents.sb3_agent import META_KEY, model_metadata
from stsf_gym.agents.training.hyperparams import (
    algorithm_class,
    check_timesteps,
    load_hyperparams,
    policy_kwargs_for_sb3,
)
from stsf_gym.agents.training.replaced_runs import keep_replaced_run
from stsf_gym.agents.training.resumed_eval import ResumableEvalCallback
from stsf_gym.agents.training.training_log import (
    EPISODES_CSV,
    EVAL_CSV,
    EpisodeLog,
    EvalLog,
    drop_rows_after,
    last_evaluation,
    plot_learning_curve,
)
from stsf_gym.agents.training.worker_envs import FailFastSubprocVecEnv
from stsf_gym.envs.config import ConfigError
from stsf_gym.envs.generated_env import generated_label, parse_world
from stsf_gym.envs.suite import load_suite
from stsf_gym.episode_env import make_episode_env, resolved_config
from stsf_gym.io import write_atomic, write_json
from stsf_gym.results.provenance import (
    code_version,
    fingerprint,
    loaded_modules,
    note_worker_modules,
    provenance,
    reference_ms,
)
from stsf_gym.wrappers import check_pose_source
from stsf_gym.yaml_layers import deep_merge, overrides_to_tree

PREFIX = "model"  # checkpoints are checkpoints/model_<timesteps>_steps.zip
EVAL_SEED_OFFSET = 10_000  # the evaluation env's seed is the training seed plus this


def env_id_for(world: str, estimator: str, suite: str | None = None) -> str | None:
    """The registered id of ``world`` (or of ``suite``) driven on ``estimator`` (None if not
    registered)."""
    base = next((i for i, w in stsf_gym.ENV_WORLDS.items() if w == world), None)
    if parse_world(world) is not None:
        base = stsf_gym.suite_id(suite) if suite else stsf_gym.GENERATED_ID
    suffix = next((s for s, e in stsf_gym.ESTIMATOR_IDS.items() if e == estimator), None)
    return base.replace("-v0", f"-{suffix}-v0") if base and suffix else None


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
    observation: dict,
    decision_steps: int,
    monitor_file: str,
    in_worker: bool,
    expert: bool = False,
) -> gym.Env:
    """One monitored env behind the policy's stack (built inside a worker process); with
    ``expert`` the follower labels every state (:class:`ExpertLabel`, demonstrations)."""
    if in_worker:  # Ctrl-C is the parent's to handle: it saves a checkpoint, then closes us
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    estimating = make_episode_env(world, estimator, env, {})
    labelled = ExpertLabel(estimating) if expert else estimating
    policy_env = policy_stack(labelled, observation, decision_steps)
    if expert:  # the expert labels every control step in the policy's features
        labelled.features = policy_env.get_wrapper_attr("observation")
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


def latest_checkpoint(out: Path) -> tuple[Path, int] | None:
    """The newest checkpoint in ``out/checkpoints`` and its timesteps, or None."""
    found = [
        (path, int(match.group(1)))
        for path in (out / "checkpoints").glob(f"{PREFIX}_*_steps.zip")
        if (match := re.fullmatch(rf"{PREFIX}_(\d+)_steps\.zip", path.name))
    ]
    return max(found, key=lambda item: item[1]) if found else None


def save_atomic(save, path: Path) -> Path:
    """Write what ``save(file)`` writes to ``path`` atomically: an interrupted save leaves
    the previous file (or none), never a cut-short one that a resume would load."""
    buffer = io.BytesIO()
    save(buffer)
    return write_atomic(path, buffer.getvalue())


def save_checkpoint(model, out: Path) -> Path:
    """Save as ``CheckpointCallback`` names it (with the replay buffer of off-policy models)."""
    path = out / "checkpoints" / f"{PREFIX}_{model.num_timesteps}_steps.zip"
    if getattr(model, "replay_buffer", None) is not None:
        name = f"{PREFIX}_replay_buffer_{model.num_timesteps}_steps.pkl"
        save_atomic(model.save_replay_buffer, path.with_name(name))
    return save_atomic(model.save, path)  # last: a checkpoint zip implies its buffer


class AtomicCheckpoint(BaseCallback):
    """Checkpoints a resume starts from, each written atomically (:func:`save_checkpoint`;
    ``CheckpointCallback`` writes in place, so a kill during a save could corrupt it).

    On-policy (PPO): after every update, at the start of the next rollout, so a kill loses at
    most the rollout under way and a resumed run goes on from a whole number of rollouts and
    ends at exactly its timesteps; the previous one is removed unless a multiple of
    ``save_freq`` steps lies between them. Off-policy (SAC): every ``save_freq`` steps, with
    the replay buffer (each step is an update: any count is a place to stop).
    """

    def __init__(self, save_freq: int, n_envs: int, out: Path) -> None:
        super().__init__()
        self.save_freq, self.n_envs, self.out = save_freq, n_envs, out
        self.rolling: Path | None = None

    def _on_training_start(self) -> None:
        self.on_policy = isinstance(self.model, OnPolicyAlgorithm)
        self.start = self.model.num_timesteps
        self.mark = self.start // self.save_freq

    def _on_rollout_start(self) -> None:
        steps = self.model.num_timesteps
        if not self.on_policy or steps == self.start:
            return
        path = save_checkpoint(self.model, self.out)
        if self.rolling is not None:
            self.rolling.unlink(missing_ok=True)
        crossed = steps // self.save_freq > self.mark
        self.rolling, self.mark = (
            (None if crossed else path),
            max(self.mark, steps // self.save_freq),
        )

    def _on_step(self) -> bool:
        if not self.on_policy and self.n_calls % max(self.save_freq // self.n_envs, 1) == 0:
            save_checkpoint(self.model, self.out)
        return True


class SaveBest(BaseCallback):
    """Run by ``EvalCallback`` on a new best mean reward: ``best/best_model.zip``, atomically."""

    def __init__(self, out: Path) -> None:
        super().__init__()
        self.path = out / "best" / "best_model.zip"

    def _on_step(self) -> bool:
        save_atomic(self.model.save, self.path)
        return True


def _resume(cls: type, out: Path, meta: dict, env: VecEnv):
    """The newest checkpoint's model on ``env``, if any; it must be the same kind of run."""
    found = latest_checkpoint(out)
    if found is None:
        return None
    path, steps = found
    saved = model_metadata(path)
    for key in ("algo", "estimator", "world", "suite"):
        if saved.get(key) != meta[key]:
            raise ConfigError(
                f"{out} holds a run with {key} {saved.get(key)!r}, not {meta[key]!r}; "
                "choose another --out"
            )
    if saved.get("made_by") != meta["made_by"]:
        stale = _set_aside(out)
        print(
            f"{out}: the checkpoints were made by other code or settings; they are kept in "
            f"{stale} and training starts afresh",
            file=sys.stderr,
        )
        return None
    model = cls.load(str(path), env=env, device="cpu")
    setattr(model, META_KEY, {**meta, "wall_time_s": saved.get("wall_time_s", 0.0)})
    buffer = path.with_name(f"{PREFIX}_replay_buffer_{steps}_steps.pkl")
    if buffer.is_file():
        model.load_replay_buffer(buffer)
    for name in (EPISODES_CSV, EVAL_CSV):
        drop_rows_after(out / name, steps)
    return model


def _set_aside(out: Path) -> Path:
    """Move ``out``'s checkpoints to a new folder under ``stale-checkpoints/``; forget the
    episodes and evaluations they logged."""
    stale = out / "stale-checkpoints"
    stale.mkdir(exist_ok=True)
    target = stale / str(len(list(stale.iterdir())))
    (out / "checkpoints").rename(target)
    for name in (EPISODES_CSV, EVAL_CSV):
        drop_rows_after(out / name, 0)
    return target


def val_successes(model, eval_env: VecEnv, episodes: int, seed: int) -> list[bool]:
    """Whether ``model``'s deterministic policy finishes each of ``episodes`` episodes of the
    evaluation env (reseeded: the same worlds each time) with success."""
    from stable_baselines3.common.evaluation import evaluate_policy

    eval_env.seed(seed)
    successes: list[bool] = []

    def record(local: dict, _: dict) -> None:
        if local["done"]:
            successes.append(bool(local["info"].get("is_success", False)))

    evaluate_policy(model, eval_env, episodes, deterministic=True, callback=record, warn=False)
    return successes


def _demonstrate(model, cfg, n_envs: int, out: Path, spec: dict, eval_env, training, seed):
    """The demonstration stage (:func:`run_demonstrations`) in envs whose states the expert
    labels; the learner is evaluated after each round on the evaluation worlds."""
    venv = make_vec_env(n_envs, out, "demonstrations", expert=True, **spec)
    layout = venv.get_attr("action_layout", [0])[0]
    stop = layout.index("stop") if "stop" in layout else None
    evaluate = partial(
        val_successes, model, eval_env, training.n_eval_episodes, seed + EVAL_SEED_OFFSET
    )
    try:
        made_by = model.stsf_meta["made_by"]
        stage = run_demonstrations(model, venv, cfg, stop, out, evaluate, seed, made_by)
        note_workers_code(venv)
        return stage
    finally:
        venv.close()


def evaluation_world(world: str) -> str:
    """Where training evaluates: generated worlds on the ``val`` split (held out from training
    and from the benchmark's ``test``), a fixed world on itself with other seeds."""
    return generated_label("val") if parse_world(world) is not None else world


def _finished(out: Path, made_by: dict, total: int) -> dict | None:
    """The summary of a run in ``out`` that the same code and settings finished (its model
    saved, ``total`` timesteps reached), else None."""
    path = out / "train.json"
    if not (path.is_file() and (out / "model.zip").is_file()):
        return None
    summary = json.loads(path.read_text())
    done = summary.get("made_by") == made_by and summary.get("timesteps", -1) >= total
    return summary if done else None


def train(
    algo: str,
    estimator: str,
    out: str | Path,
    timesteps: int | None = None,
    seed: int = 0,
    world: str = "irl_corridor",
    config: str | Path | None = None,
    overrides: dict | None = None,
    n_envs: int | None = None,
    progress_bar: bool = True,
    suite: str | None = None,
) -> dict:
    """Train (or continue training) until ``timesteps``; return the summary in train.json.
    With ``suite`` the agent trains on the suite's train worlds under its task (its settings
    over the hyper-parameter file's ``env``) and is evaluated on its ``val`` worlds."""
    import torch

    check_pose_source(estimator)
    if suite is not None:
        world = generated_label("train")
    hp = load_hyperparams(
        algo, env_id_for(world, estimator, suite), config, overrides, suite is not None
    )
    cfg = hp.training
    env_settings = cfg.env
    if suite is not None:  # the suite over the file's env, the command line's over both
        on_command_line = overrides_to_tree(overrides or {}).get("env", {})
        env_settings = deep_merge(
            deep_merge(cfg.env, load_suite(suite).episode_env), on_command_line
        )
    n_envs = cfg.n_envs if n_envs is None else n_envs
    total = cfg.n_timesteps if timesteps is None else timesteps
    demonstrations = demonstration_config(cfg.demonstrations)
    least = 0 if demonstrations.enabled else 1  # demonstrations alone are a whole run
    if n_envs < 1 or total < least:
        raise ConfigError(
            f"--n-envs must be at least 1 and --timesteps at least {least}, got {n_envs}, {total}"
        )
    check_timesteps(hp, n_envs, total)
    torch.set_num_threads(1)
    train_settings = deep_merge(env_settings, cfg.train_env)
    check_training_env(world, estimator, train_settings, seed)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    machine = {"reference_ms_before": reference_ms(), "load_average_before": os.getloadavg()}
    observation = asdict(observation_config(cfg.observation))
    spec = {
        "world": world,
        "estimator": estimator,
        "env": env_settings,
        "observation": observation,
        "decision_steps": cfg.decision_steps,
    }
    training = {k: v for k, v in asdict(cfg).items() if k not in ("env", "observation")}
    training["demonstrations"] = asdict(demonstrations)  # defaults too: they can change
    hyperparams = {"section": hp.section, **training, **hp.algo_kwargs, "n_envs": n_envs}
    resolved = {
        **resolved_config(world, estimator, env_settings),
        "suite": suite,
        "evaluation_world": evaluation_world(world),
        "algo": algo,
        "hyperparams": hyperparams,
        "observation": observation,
    }
    meta = {
        "algo": algo,
        "seed": seed,
        "suite": suite,
        "evaluation_world": evaluation_world(world),
        **spec,
        "hyperparams": hyperparams,
        "wall_time_s": 0.0,
        "made_by": fingerprint(resolved),
        "provenance": provenance(resolved, [seed]),
    }
    finished = _finished(out, meta["made_by"], total)
    if finished is not None:  # a campaign's rerun: this run is done, its files stay untouched
        return finished
    keep_replaced_run(out, meta["made_by"])  # a run finished by other code or settings: kept
    cls = algorithm_class(algo)
    train_spec = {**spec, "env": train_settings}
    train_env = make_vec_env(n_envs, out, "train", **train_spec)
    eval_env = make_vec_env(1, out, "eval", **{**spec, "world": evaluation_world(world)})
    eval_env.seed(seed + EVAL_SEED_OFFSET)
    try:
        model = _resume(cls, out, meta, train_env)
        if model is None:
            model = cls(
                cfg.policy,
                train_env,
                policy_kwargs=policy_kwargs_for_sb3(cfg.policy_kwargs),
                tensorboard_log=str(out / "tb"),
                seed=seed,
                device="cpu",
                **hp.algo_kwargs,
            )
            setattr(model, META_KEY, meta)
        if demonstrations.enabled and model.num_timesteps == 0:  # the stage before RL
            stage = _demonstrate(
                model, demonstrations, n_envs, out, train_spec, eval_env, cfg, seed
            )
            model.stsf_meta["demonstrations"] = stage
            model.stsf_meta["wall_time_s"] = stage["wall_time_s"]  # RL has not started
        start = model.num_timesteps
        train_env.seed(seed + start)
        callbacks = CallbackList(
            [
                EpisodeLog(out, model.stsf_meta["wall_time_s"]),
                AtomicCheckpoint(cfg.checkpoint_freq, n_envs, out),
                ResumableEvalCallback(  # the same timesteps when resumed (resumed_eval.py)
                    eval_env,
                    out=out,
                    n_eval_episodes=cfg.n_eval_episodes,
                    eval_freq=max(cfg.eval_freq // n_envs, 1),
                    log_path=str(out / "eval"),
                    callback_on_new_best=SaveBest(out),
                    deterministic=True,
                    callback_after_eval=EvalLog(out),
                    verbose=0,
                ),
            ]
        )
        started = time.perf_counter()
        if total > start:
            try:
                with warnings.catch_warnings():
                    # one evaluation env needs no worker process: the vec env types differ
                    warnings.filterwarnings("ignore", "Training and eval env are not of the same")
                    model.learn(
                        total - start,
                        callback=callbacks,
                        reset_num_timesteps=False,
                        progress_bar=progress_bar,
                        tb_log_name=algo,
                    )
            except KeyboardInterrupt:
                if not isinstance(model, OnPolicyAlgorithm):  # PPO: its last update is saved
                    save_checkpoint(model, out)
                raise
        session = time.perf_counter() - started
        note_workers_code(train_env)
    finally:
        train_env.close()
        eval_env.close()
    if model.num_timesteps > start:
        save_checkpoint(model, out)
    # the code as the run loaded it by now, here and in the env processes
    model.stsf_meta["provenance"] = {**model.stsf_meta["provenance"], "stsf_gym": code_version()}
    save_atomic(model.save, out / "model.zip")
    summary = {
        **{k: v for k, v in model.stsf_meta.items() if k != "wall_time_s"},
        "timesteps": model.num_timesteps,
        "resumed_from": start,
        "n_envs": n_envs,
        "wall_time_s": model.stsf_meta["wall_time_s"],
        "session_wall_time_s": session,
        "steps_per_second": (model.num_timesteps - start) / session if session > 0 else None,
        # the machine's speed beside the times (stsf-gym bench's reference workload, ms)
        "machine": {**machine, "reference_ms_after": reference_ms()},
        "last_evaluation": last_evaluation(out),
        "model": str(out / "model.zip"),
        "learning_curve": str(plot_learning_curve(out, f"{algo.upper()} on {estimator}")),
    }
    write_json(out / "train.json", summary)
    return summary
