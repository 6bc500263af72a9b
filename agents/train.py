"""``stsf-gym train``: a PPO or SAC agent driving on one pose source, resumable.

The agent runs in the same env as every evaluated agent (``make_episode_env``: the pan camera
pointed by :class:`PoseEstimateWrapper`), with :class:`PolicyObservation` on top and
``Monitor`` outside. ``OUT`` receives ``checkpoints/``, ``tb/`` (TensorBoard), ``monitor/``,
``eval/`` and ``best/`` (the best evaluated model), ``episodes.csv``, ``eval.csv``,
``learning_curve.png``, ``model.zip`` and ``train.json``. Rerunning with the same ``OUT``
continues from the newest checkpoint; Ctrl-C saves one first.
"""

from __future__ import annotations

import io
import re
import signal
import time
import warnings
from dataclasses import asdict
from functools import partial
from pathlib import Path

import gymnasium as gym
from stable_baselines3.common.callbacks import BaseCallback, CallbackList, EvalCallback
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecEnv

import stsf_gym
from stsf_gym.agents.hyperparams import algorithm_class, load_hyperparams, policy_kwargs_for_sb3
from stsf_gym.agents.observation import PolicyObservation, observation_config
from stsf_gym.agents.sb3_agent import META_KEY, model_metadata
from stsf_gym.agents.training_log import (
    EPISODES_CSV,
    EVAL_CSV,
    EpisodeLog,
    EvalLog,
    drop_rows_after,
    last_evaluation,
    plot_learning_curve,
)
from stsf_gym.envs.config import ConfigError
from stsf_gym.envs.generated_env import parse_world
from stsf_gym.episode_env import make_episode_env
from stsf_gym.io import write_atomic, write_json
from stsf_gym.wrappers import check_pose_source

PREFIX = "model"  # checkpoints are checkpoints/model_<timesteps>_steps.zip
EVAL_SEED_OFFSET = 10_000  # the evaluation env's seed is the training seed plus this


def env_id_for(world: str, estimator: str) -> str | None:
    """The registered id of ``world`` driven on ``estimator`` (None if not registered)."""
    base = next((i for i, w in stsf_gym.ENV_WORLDS.items() if w == world), None)
    if parse_world(world) is not None:
        base = stsf_gym.GENERATED_ID
    suffix = next((s for s, e in stsf_gym.ESTIMATOR_IDS.items() if e == estimator), None)
    return base.replace("-v0", f"-{suffix}-v0") if base and suffix else None


def make_training_env(
    world: str, estimator: str, env: dict, observation: dict, monitor_file: str, in_worker: bool
) -> gym.Env:
    """One monitored env with the policy's observation (built inside a worker process)."""
    if in_worker:  # Ctrl-C is the parent's to handle: it saves a checkpoint, then closes us
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    policy_env = PolicyObservation(
        make_episode_env(world, estimator, env, {}), observation_config(observation)
    )
    fresh = not Path(f"{monitor_file}.{Monitor.EXT}").is_file()
    return Monitor(policy_env, monitor_file, info_keywords=("is_success",), override_existing=fresh)


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
    return SubprocVecEnv(factories, "forkserver") if in_workers else DummyVecEnv(factories)


def latest_checkpoint(out: Path) -> tuple[Path, int] | None:
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
    """Every ``save_freq`` calls, :func:`save_checkpoint` (``CheckpointCallback`` writes in
    place, so an interrupt during a save could leave a corrupt newest checkpoint)."""

    def __init__(self, save_freq: int, out: Path) -> None:
        super().__init__()
        self.save_freq, self.out = save_freq, out

    def _on_step(self) -> bool:
        if self.n_calls % self.save_freq == 0:
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
    for key in ("algo", "estimator", "world"):
        if saved.get(key) != meta[key]:
            raise ConfigError(
                f"{out} holds a run with {key} {saved.get(key)!r}, not {meta[key]!r}; "
                "choose another --out"
            )
    model = cls.load(str(path), env=env, device="cpu")
    setattr(model, META_KEY, {**meta, "wall_time_s": saved.get("wall_time_s", 0.0)})
    buffer = path.with_name(f"{PREFIX}_replay_buffer_{steps}_steps.pkl")
    if buffer.is_file():
        model.load_replay_buffer(buffer)
    for name in (EPISODES_CSV, EVAL_CSV):
        drop_rows_after(out / name, steps)
    return model


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
) -> dict:
    """Train (or continue training) until ``timesteps``; return the summary in train.json."""
    import torch

    check_pose_source(estimator)
    hp = load_hyperparams(algo, env_id_for(world, estimator), config, overrides)
    cfg = hp.training
    n_envs = cfg.n_envs if n_envs is None else n_envs
    total = cfg.n_timesteps if timesteps is None else timesteps
    if n_envs < 1 or total < 1:
        raise ConfigError(f"--n-envs and --timesteps must be at least 1, got {n_envs}, {total}")
    torch.set_num_threads(1)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    observation = asdict(observation_config(cfg.observation))
    spec = {"world": world, "estimator": estimator, "env": cfg.env, "observation": observation}
    training = {k: v for k, v in asdict(cfg).items() if k not in ("env", "observation")}
    hyperparams = {"section": hp.section, **training, **hp.algo_kwargs, "n_envs": n_envs}
    meta = {"algo": algo, "seed": seed, **spec, "hyperparams": hyperparams, "wall_time_s": 0.0}
    cls = algorithm_class(algo)
    train_env = make_vec_env(n_envs, out, "train", **spec)
    eval_env = make_vec_env(1, out, "eval", **spec)
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
        start = model.num_timesteps
        train_env.seed(seed + start)
        callbacks = CallbackList(
            [
                EpisodeLog(out, model.stsf_meta["wall_time_s"]),
                AtomicCheckpoint(max(cfg.checkpoint_freq // n_envs, 1), out),
                EvalCallback(
                    eval_env,
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
                save_checkpoint(model, out)
                raise
        session = time.perf_counter() - started
    finally:
        train_env.close()
        eval_env.close()
    if model.num_timesteps > start:
        save_checkpoint(model, out)
    save_atomic(model.save, out / "model.zip")
    summary = {
        **{k: v for k, v in model.stsf_meta.items() if k != "wall_time_s"},
        "timesteps": model.num_timesteps,
        "resumed_from": start,
        "n_envs": n_envs,
        "wall_time_s": model.stsf_meta["wall_time_s"],
        "session_wall_time_s": session,
        "steps_per_second": (model.num_timesteps - start) / session if session > 0 else None,
        "last_evaluation": last_evaluation(out),
        "model": str(out / "model.zip"),
        "learning_curve": str(plot_learning_curve(out, f"{algo.upper()} on {estimator}")),
    }
    write_json(out / "train.json", summary)
    return summary
