"""What the tests share besides fixtures (those are in ``conftest.py``): the repository's
root, its scripts loaded as modules, an episode driven by a list of actions, the id matrices of
the two tiers, the tiny learner's settings and its training, and rl-zoo3 run as its users run it.
Tests import these with ``from helpers import ...`` (pytest puts ``tests/`` on the path)."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import gymnasium as gym
import numpy as np
import pytest

import stsf_gym

#: The repository's root (the folder above ``tests/``).
ROOT = Path(__file__).resolve().parent.parent

NOISE_FREE_ENCODERS = {
    "encoders__radius_error_std": 0.0,
    "encoders__wheelbase_error_std": 0.0,
    "encoders__slip_std": 0.0,
}


def load_script(relative: str) -> ModuleType:
    """The script at ``relative`` (to the repository's root, e.g. in ``benchmarks/`` or
    ``examples/``) loaded as a fresh module."""
    path = ROOT / relative
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def drive(env, actions, seed: int = 0, options: dict | None = None):
    """Reset with ``seed`` and apply ``actions``; return the list of (obs, info) after each."""
    obs, info = env.reset(seed=seed, options=options)
    history = [(obs, info)]
    for action in actions:
        obs, _, terminated, truncated, info = env.step(np.asarray(action, np.float32))
        history.append((obs, info))
        if terminated or truncated:
            break
    return history


def _base_and_source(env_id: str) -> tuple[str, str | None]:
    """``stsf_gym/Suite-Sparse-EKF-v0`` -> ("Suite-Sparse", "EKF"); a base id's source is None."""
    name = env_id.split("/", 1)[1].removesuffix("-v0")
    base, _, last = name.rpartition("-")
    if base and last in stsf_gym.ESTIMATOR_IDS:
        return base, last
    return name, None


def id_matrix(env_ids) -> list:
    """``env_ids`` as pytest params: a covering few in the default tier (each base world once
    and each pose source once, paired off in turn, and one bare base id), every other one
    marked ``every_id``."""
    parts = {env_id: _base_and_source(env_id) for env_id in env_ids}
    bases = sorted({base for base, _ in parts.values()})
    sources = sorted({source for _, source in parts.values() if source})
    turns = max(len(bases), len(sources))
    covering = {(bases[i % len(bases)], sources[i % len(sources)]) for i in range(turns)}
    covering.add((bases[0], None))
    return [
        pytest.param(env_id, id=env_id, marks=() if part in covering else pytest.mark.every_id)
        for env_id, part in sorted(parts.items())
    ]


def registered_ids() -> list[str]:
    """Every id the package registers."""
    return sorted(i for i in gym.registry if i.startswith("stsf_gym/"))


#: The corridor suite's learner, tiny: one expert leg, no DAgger round, 1 val route, then three
#: PPO updates on the reward from the clone (the first trains the critic alone).
TINY_LEARNER = {
    "demonstrations.expert_episodes": 1,
    "demonstrations.rounds": 0,
    "demonstrations.cloning.epochs": 2,
    "n_eval_episodes": 1,
    "eval_freq": 64,
    "env.sim.max_episode_seconds": 6.0,
    "train_env.sim.max_episode_seconds": 6.0,
    "train_env.task.leg_min": 1.0,
    "train_env.task.leg_max": 1.5,
    "n_steps": 32,
    "batch_size": 32,
    "n_epochs": 2,
    "finetune.timesteps": 96,
    "finetune.value_warmup_steps": 32,
    "finetune.clone_kl_coef": 0.5,
    "finetune.learning_rate": 1.0e-4,
}


def train_tiny_learner(out, **extra) -> dict:
    """``dagger+ppo`` on the corridor suite's true pose with :data:`TINY_LEARNER` into ``out``."""
    from stsf_gym.agents.training.train import train

    return train(
        "dagger+ppo", "truth", out, n_envs=1, overrides=TINY_LEARNER, progress_bar=False,
        suite="corridor", **extra,
    )  # fmt: skip


def run_rl_zoo3(env_id: str, folder, *arguments: str):
    """``python -m rl_zoo3.train`` as its users run it: PPO on ``env_id`` with the package's
    zoo file, 128 steps in updates of 64, logs under ``folder``; the finished process."""
    command = [sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", env_id]
    command += ["--gym-packages", "stsf_gym", "--conf-file", "stsf_gym.agents.zoo", "-n", "128"]
    command += ["--seed", "0", "-f", str(folder), *arguments]
    command += ["-params", "n_envs:1", "n_steps:64", "batch_size:32"]
    return subprocess.run(
        command,
        capture_output=True,
        text=True,
        timeout=300,
        cwd=folder,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )


def interrupt_in_the_third_rollout(monkeypatch, run) -> None:
    """``run()`` (a tiny training of :data:`TINY_LEARNER`'s rollouts of 32) stopped by a
    KeyboardInterrupt once past 70 timesteps, in its third rollout, as Ctrl-C stops it."""
    from stsf_gym.agents.training.training_log import EpisodeLog

    original = EpisodeLog._on_step

    def interrupt(self):
        original(self)
        if self.num_timesteps > 70:
            raise KeyboardInterrupt
        return True

    monkeypatch.setattr(EpisodeLog, "_on_step", interrupt)
    with pytest.raises(KeyboardInterrupt):
        run()
    monkeypatch.setattr(EpisodeLog, "_on_step", original)


def training_folder(root: Path, seeds, source: Path) -> Path:
    """A `train --seeds N` folder holding the shipped agent ``source``'s models of ``seeds``
    (``stsf_gym.agents.pretrained.MODELS / SUITE / NAME``), as the shipping tests ship."""
    for seed in seeds:
        run = root / f"seed-{seed}"
        run.mkdir(parents=True)
        shutil.copyfile(source / f"seed-{seed}.zip", run / "model.zip")
        shutil.copyfile(source / f"seed-{seed}.json", run / "train.json")
    return root
