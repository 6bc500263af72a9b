"""Shared fixtures: small, fast envs (the camera off unless a test needs it), and the command
line run in the test's process."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import stsf_gym  # noqa: F401 - registers the ids

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
