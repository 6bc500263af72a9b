"""Checkpoints of a training run, each written atomically, and the resume from them.

A checkpoint made by other code or another resolved configuration (its
:func:`~stsf_gym.results.fingerprint.fingerprint`, ``made_by``, differs) is not resumed: the
run says so, moves the old checkpoints to ``stale-checkpoints/`` and starts afresh.
"""

from __future__ import annotations

import io
import json
import re
import sys
from functools import partial
from pathlib import Path

from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
from stable_baselines3.common.vec_env import VecEnv

from stsf_gym.agents.model_files import META_KEY, model_metadata
from stsf_gym.agents.training.hyperparams import learner_of
from stsf_gym.agents.training.training_log import (
    EPISODES_CSV,
    EVAL_CSV,
    EVALUATIONS_JSON,
    drop_rows_after,
)
from stsf_gym.io import write_atomic
from stsf_gym.validation import ConfigError

PREFIX = "model"  # checkpoints are checkpoints/model_<timesteps>_steps.zip


def latest_checkpoint(out: Path) -> tuple[Path, int] | None:
    """The newest checkpoint in ``out/checkpoints`` and its timesteps, or None."""
    found = [
        (path, int(match.group(1)))
        for path in (out / "checkpoints").glob(f"{PREFIX}_*_steps.zip")
        if (match := re.fullmatch(rf"{PREFIX}_(\d+)_steps\.zip", path.name))
    ]
    return max(found, key=lambda item: item[1]) if found else None


def resumable_steps(out: Path, made_by: str) -> int:
    """The decisions a rerun into ``out`` resumes from: its newest checkpoint's, when the same
    code and settings (``made_by``) made it (:func:`resume` sets others aside), else 0."""
    found = latest_checkpoint(out)
    if found is None or model_metadata(found[0]).get("made_by") != made_by:
        return 0
    return found[1]


def save_atomic(save, path: Path) -> Path:
    """Write what ``save(file)`` writes to ``path`` atomically: an interrupted save leaves
    the previous file (or none), never a cut-short one that a resume would load."""
    buffer = io.BytesIO()
    save(buffer)
    return write_atomic(path, buffer.getvalue())


#: Attributes a saved model leaves out: where this machine logged TensorBoard (a path of the
#: machine, which a resume sets again under its own folder: :func:`load_checkpoint`'s load).
MACHINE_ATTRIBUTES = ["tensorboard_log"]


def save_model(model, path: Path) -> Path:
    """``model`` saved at ``path`` atomically (:func:`save_atomic`), without the machine's
    paths (:data:`MACHINE_ATTRIBUTES`)."""
    return save_atomic(partial(model.save, exclude=MACHINE_ATTRIBUTES), path)


def save_checkpoint(model, out: Path) -> Path:
    """Save as ``CheckpointCallback`` names it (with the replay buffer of off-policy models)."""
    path = out / "checkpoints" / f"{PREFIX}_{model.num_timesteps}_steps.zip"
    if getattr(model, "replay_buffer", None) is not None:
        name = f"{PREFIX}_replay_buffer_{model.num_timesteps}_steps.pkl"
        save_atomic(model.save_replay_buffer, path.with_name(name))
    return save_model(model, path)  # last: a checkpoint zip implies its buffer


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
        save_model(self.model, self.path)
        return True


def resume(cls: type, out: Path, meta: dict, env: VecEnv):
    """The newest checkpoint's model on ``env``, if any; it must be the same kind of run (the
    same learner: a run's recorded ``algo`` changes with its stages, not its checkpoints')."""
    found = latest_checkpoint(out)
    if found is None:
        return None
    path, steps = found
    saved = model_metadata(path)
    mine = {**meta, "algo": learner_of(meta["algo"])}
    for key in ("algo", "estimator", "world", "suite"):
        theirs = learner_of(saved[key]) if key == "algo" else saved.get(key)
        if theirs != mine[key]:
            raise ConfigError(
                f"{out} holds a run with {key} {theirs!r}, not {mine[key]!r}; choose another --out"
            )
    if saved.get("made_by") != meta["made_by"]:
        stale = set_aside(out)
        print(
            f"{out}: the checkpoints were made by other code or settings; they are kept in "
            f"{stale} and training starts afresh",
            file=sys.stderr,
        )
        return None
    model = cls.load(str(path), env=env, device="cpu", tensorboard_log=str(out / "tb"))
    setattr(model, META_KEY, {**saved, **meta, "wall_time_s": saved.get("wall_time_s", 0.0)})
    buffer = path.with_name(f"{PREFIX}_replay_buffer_{steps}_steps.pkl")
    if buffer.is_file():
        model.load_replay_buffer(buffer)
    for name in (EPISODES_CSV, EVAL_CSV, EVALUATIONS_JSON):
        drop_rows_after(out / name, steps)
    return model


def set_aside(out: Path) -> Path:
    """Move ``out``'s checkpoints to a new folder under ``stale-checkpoints/``; forget the
    episodes and evaluations they logged."""
    stale = out / "stale-checkpoints"
    stale.mkdir(exist_ok=True)
    target = stale / str(len(list(stale.iterdir())))
    (out / "checkpoints").rename(target)
    for name in (EPISODES_CSV, EVAL_CSV, EVALUATIONS_JSON):
        drop_rows_after(out / name, 0)
    return target


def finished_summary(out: Path, made_by: str, total: int) -> dict | None:
    """The summary of a run in ``out`` that the same code and settings finished (its model
    saved, ``total`` timesteps reached), else None."""
    path = out / "train.json"
    if not (path.is_file() and (out / "model.zip").is_file()):
        return None
    summary = json.loads(path.read_text())
    done = summary.get("made_by") == made_by and summary.get("timesteps", -1) >= total
    return summary if done else None
