"""rl-zoo3 runs on the registered ids with ``--conf-file stsf_gym.agents.zoo``."""

import re

import pytest
from helpers import id_matrix, run_rl_zoo3

import stsf_gym
from stsf_gym.agents.training.hyperparams import load_hyperparams
from stsf_gym.agents.zoo import hyperparams, zoo_section
from stsf_gym.config_files import SUITE_DIR, deep_merge
from stsf_gym.envs.suite import load_suite


def test_every_estimating_id_has_a_section():
    """Each world's, the generated worlds' and each suite's id per pose source (the suites'
    were missing: ``Hyperparameters not found for ppo-stsf_gym/Suite-Corridor-STSF-v0``)."""
    bases = [*stsf_gym.ENV_WORLDS, stsf_gym.GENERATED_ID]
    bases += [stsf_gym.suite_id(path.stem) for path in SUITE_DIR.glob("*.yaml")]
    expected = {b.replace("-v0", f"-{s}-v0") for b in bases for s in stsf_gym.ESTIMATOR_IDS}
    suites = [path.stem for path in SUITE_DIR.glob("*.yaml")]
    expected |= {stsf_gym.rl_id(s, e) for s in suites for e in stsf_gym.ESTIMATOR_IDS.values()}
    assert len(bases) >= 6 and set(hyperparams) == expected
    assert "env_wrapper" not in hyperparams["stsf_gym/RL-Sparse-STSF-v0"]  # the id is the task
    section = zoo_section("ppo", "stsf_gym/Suite-Corridor-Odometry-v0")
    suite = section["env_kwargs"]
    hp = load_hyperparams("ppo", "stsf_gym/Suite-Corridor-Odometry-v0", suite=True).training
    trained = deep_merge(hp.env, load_suite("corridor").env)
    assert suite == trained  # as `stsf-gym train --suite corridor` trains: odometry, camera off
    assert suite["camera"] == {"mode": "fast", "enabled": False}
    assert suite["task"]["protocol"] == "declare" and suite["task"]["stop_action"] is True
    assert [next(iter(w)) for w in section["env_wrapper"]][-1].endswith("DecisionInterval")


def test_sections_follow_the_training_config():
    assert "stsf_gym/Corridor-STSF-v0" in hyperparams
    assert "stsf_gym/Straight10m-Truth-v0" in hyperparams
    assert "stsf_gym/Corridor-v0" not in hyperparams  # no estimate: no policy observation
    truth = zoo_section("ppo", "stsf_gym/Corridor-Truth-v0")
    assert truth["env_kwargs"]["camera"] == {"mode": "fast", "enabled": False}
    assert truth["policy"] == "MlpPolicy" and truth["n_steps"] == 1024


@pytest.mark.parametrize("env_id", id_matrix(hyperparams))
def test_rl_zoo3_builds_the_agent_on_every_estimating_id(tmp_path, env_id):
    """rl-zoo3's own ExperimentManager reads each id's section, builds the env and the model,
    and the env steps (what ``rl_zoo3.train`` does before learning)."""
    import argparse

    import numpy as np
    from rl_zoo3.exp_manager import ExperimentManager

    manager = ExperimentManager(
        argparse.Namespace(),
        "ppo",
        env_id,
        str(tmp_path),
        n_timesteps=64,
        eval_freq=-1,
        hyperparams={"n_envs": 1, "n_steps": 64, "batch_size": 32},
        config="stsf_gym.agents.zoo",
        verbose=0,
    )
    model, _ = manager.setup_experiment()
    try:
        obs = model.env.reset()
        obs, *_ = model.env.step(np.array([model.action_space.sample()]))
        assert obs.shape == (1, *model.observation_space.shape)
    finally:
        model.env.close()


@pytest.mark.slow
@pytest.mark.parametrize(
    "env_id", ["stsf_gym/Straight10m-Truth-v0", "stsf_gym/Suite-Corridor-STSF-v0"]
)
def test_rl_zoo3_trains_ppo_through_gym_packages(tmp_path, env_id):
    eval_env = ["--eval-env-kwargs", "camera:{'enabled':False}"]
    result = run_rl_zoo3(env_id, tmp_path, "--eval-freq", "-1", *eval_env)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    assert re.search(r"total_timesteps\s*\|\s*128\b", result.stdout), result.stdout[-2000:]
    (model,) = tmp_path.glob(f"ppo/{env_id.replace('/', '-')}_1/*.zip")
    assert model.stat().st_size > 10_000
