"""Shared fixtures: small, fast envs (the camera off unless a test needs it), and the command
line run in the test's process."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import stsf_gym

NOISE_FREE_ENCODERS = {
    "encoders__radius_error_std": 0.0,
    "encoders__wheelbase_error_std": 0.0,
    "encoders__slip_std": 0.0,
}


@pytest.fixture
def make_env():
    """Factory of envs that are closed after the test."""
    envs = []

    def factory(env_id: str = "stsf_gym/Corridor-v0", **kwargs):
        env = gym.make(env_id, **kwargs)
        envs.append(env)
        return env

    yield factory
    for env in envs:
        env.close()


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


@pytest.fixture
def run_cli(monkeypatch, capsys):
    """``stsf_gym.cli.main(argv)`` -> (exit code, stderr), C stdout left alone."""
    import stsf_gym.cli as cli

    monkeypatch.setattr(cli, "_silence_c_stdout", lambda: None)

    def run(*argv: str) -> tuple[int, str]:
        code = cli.main(list(argv))
        return code, capsys.readouterr().err

    return run


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
