"""The fixtures the tests share: small, fast envs (the camera off unless a test needs it), the
command line run in the test's process and one tiny trained model. Everything else the tests
share is in ``helpers.py``."""

from __future__ import annotations

import gymnasium as gym
import pytest
from helpers import train_tiny_learner


@pytest.fixture(autouse=True, scope="session")
def measured_rates(tmp_path_factory):
    """The runs of the tests keep their measured rates apart from the user's (subprocesses
    inherit the variable)."""
    import os

    from stsf_gym.experiments.jobs.estimate import RATES_ENV

    os.environ[RATES_ENV] = str(tmp_path_factory.mktemp("rates") / "rates.json")


@pytest.fixture(autouse=True)
def own_run():
    """Each test is a run of its own (:mod:`stsf_gym.results.run_context`): it sees no earlier
    test's worker modules, data files or command."""
    from stsf_gym.results.run_context import run_context

    with run_context() as run:
        yield run


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


@pytest.fixture
def run_cli(monkeypatch, capsys):
    """``stsf_gym.cli.main(argv)`` -> (exit code, stderr), C stdout left alone."""
    import stsf_gym.cli as cli

    monkeypatch.setattr(cli, "_silence_c_stdout", lambda: None)

    def run(*argv: str) -> tuple[int, str]:
        code = cli.main(list(argv))
        return code, capsys.readouterr().err

    return run


@pytest.fixture(scope="session")
def tiny_learner(tmp_path_factory):
    """One tiny trained model, made once per pytest run and shared by the agent tests: the
    training folder (``model.zip``, ``train.json``, the clone in ``finetune/clone.zip``) and
    its summary."""
    out = tmp_path_factory.mktemp("tiny-learner")
    return out, train_tiny_learner(out)
