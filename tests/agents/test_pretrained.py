"""Agents shipped trained: each loads and drives an episode, is listed, and is flagged stale
when the code changes what it sees."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from stsf_gym.agents import pretrained
from stsf_gym.agents.registry import make_agent
from stsf_gym.experiments.benchmark.trained import expand_agents, training_group
from stsf_gym.validation import ConfigError

SHIPPED = pretrained.names()


def test_agents_are_shipped_under_what_trained_them_and_old_names_are_aliases():
    assert "pretrained:corridor/dagger-truth" in SHIPPED
    for name in SHIPPED:  # each named by what ran: a reward stage only where it says so
        record = pretrained.summary(name)
        assert name.endswith(f"/{record['algo']}-{record['pose_source']}")
        steps = [make_agent(str(m)).trained_on()["timesteps"] for m in pretrained.models(name)]
        assert all(steps) if "+ppo" in record["algo"] else not any(steps)
    old, new = "pretrained:corridor/ppo-truth", "pretrained:corridor/dagger-truth"
    assert pretrained.aliases()[old] == new and old not in SHIPPED
    assert expand_agents([old]) == expand_agents([new])
    assert pretrained.summary(old)["name"] == new


@pytest.mark.slow
@pytest.mark.parametrize("name", SHIPPED)
def test_each_seed_loads_and_drives_an_episode(name):
    record = pretrained.summary(name)
    for model in pretrained.models(name):
        agent = make_agent(str(model))
        assert agent.trained_on()["estimator"] == record["pose_source"]
        short = {"sim": {"max_episode_seconds": 10.0}}
        env = pretrained.suite_test_env(agent, record["suite"], record["pose_source"], short)
        obs, _ = env.reset(seed=1)
        agent.begin(env)
        done, steps = False, 0
        while not done:
            obs, _, terminated, truncated, info = env.step(agent.act(obs))
            done, steps = terminated or truncated, steps + 1
        env.close()
        assert steps >= 20 and info["distance_travelled"] > 0.5  # it drove, to the end


def test_stsf_gym_agents_lists_them_as_json():
    done = subprocess.run(
        [sys.executable, "-m", "stsf_gym.cli", "agents", "--json"],
        capture_output=True,
        text=True,
        check=True,
    )
    rows = json.loads(done.stdout.strip().splitlines()[-1])
    assert [r["name"] for r in rows] == SHIPPED
    aliases = {a: r["name"] for r in rows for a in r["aliases"]}
    assert aliases == pretrained.aliases()
    for row in rows:
        assert {"algo", "suite", "pose_source", "seeds", "val_success", "provenance"} <= set(row)
        assert len(row["val_success"]) == len(row["seeds"]) >= 1


@pytest.mark.slow
def test_none_is_stale_and_a_change_of_what_they_see_is_flagged(monkeypatch):
    assert pretrained.stale() == []
    from stsf_gym.agents.observation import PolicyObservation

    seen = PolicyObservation.observation
    monkeypatch.setattr(
        PolicyObservation, "observation", lambda self, obs: seen(self, obs) + np.float32(1e-3)
    )
    assert pretrained.moved("pretrained:corridor/dagger-truth", 0)


def test_a_shipped_name_expands_to_its_seeds_and_groups_under_its_name():
    models = expand_agents(["pretrained:corridor/ppo-truth"])  # an alias: the same models
    assert len(models) == len(pretrained.summary("pretrained:corridor/dagger-truth")["seeds"])
    assert {training_group(m) for m in models} == {"pretrained:corridor/dagger-truth"}
    with pytest.raises(ConfigError, match="no shipped agent 'pretrained:corridor/ppo-nothing'"):
        expand_agents(["pretrained:corridor/ppo-nothing"])


def test_a_run_that_names_a_shipped_agent_counts_its_models_as_loaded_code():
    """Results quoted from a shipped agent go stale when it is shipped again."""
    from stsf_gym.results.code_identity import file_digest, loaded_code

    models = expand_agents(["pretrained:corridor/ppo-truth"])
    code = loaded_code()
    for model in map(Path, models):
        path = f"agents/pretrained/trained-models/corridor/dagger-truth/{model.name}"
        assert code[path] == file_digest(model)


def test_the_accuracy_curve_takes_a_shipped_agent(tmp_path):
    """``accuracy-curve --agent pretrained:...``: one curve per training seed."""
    from stsf_gym.cli import main

    argv = "accuracy-curve --agent pretrained:corridor/ppo-truth --suite corridor --seeds 1"
    argv += " --levels 1 --workers 1 --set sim.max_episode_seconds=3"
    assert main([*argv.split(), "--estimators", "", "--out", str(tmp_path)]) == 0
    curves = json.loads((tmp_path / "curve.json").read_text())["curves"]
    assert len(curves) == len(pretrained.summary("pretrained:corridor/ppo-truth")["seeds"])
