"""One resolver of agent names: ``make_agent`` takes every name the CLI takes, a model's env is
the one it was trained for, an env that differs from a model's settings is refused, and every
model is its own row of a comparison, its seeds aggregated as the benchmark does."""

import json
from pathlib import Path
from types import SimpleNamespace

import pytest

from stsf_gym.agents import pretrained
from stsf_gym.agents.decision_interval import DecisionInterval
from stsf_gym.agents.model_files import trained_algo
from stsf_gym.agents.observation import PolicyObservation, observation_config
from stsf_gym.agents.registry import make_agent, make_agents
from stsf_gym.agents.resolve import model_path, resolve_agent, training_group
from stsf_gym.agents.trained_agent import SB3Agent, wrap_for_model
from stsf_gym.experiments.benchmark.trained import agent_name, expand_agents
from stsf_gym.experiments.compare import judged_alike, seed_aggregates
from stsf_gym.validation import ConfigError

SHIPPED = "pretrained:corridor/dagger-truth"
EKF_AGENT = "pretrained:sparse/dagger-ekf"
QUICK = {"camera": {"enabled": False}, "sim": {"max_episode_seconds": 3.0}}


def test_make_agent_takes_a_shipped_name_an_alias_a_folder_a_zip_and_a_scripted_name(tmp_path):
    models = pretrained.models(SHIPPED)
    for name in (SHIPPED, "pretrained:corridor/ppo-truth"):
        agents = make_agents(name)
        assert [a.path.resolve() for a in agents] == models
        assert make_agent(name).path.resolve() == models[0]  # its first seed
        assert make_agent(name).trained_on()["algo"] == "dagger"  # what ran, not the SB3 class
    run = tmp_path / "run"
    for seed, model in enumerate(models[:2]):
        (run / f"seed-{seed}").mkdir(parents=True)
        (run / f"seed-{seed}" / "model.zip").write_bytes(model.read_bytes())
    assert [a.digest for a in make_agents(str(run))] == [a.digest for a in make_agents(SHIPPED)[:2]]
    assert make_agent(str(models[1])).digest == make_agents(SHIPPED)[1].digest
    assert make_agent("follower").label() == "follower"
    assert make_agent("cautious-follower").label() == "cautious-follower"
    with pytest.raises(ConfigError, match="no trained model"):
        make_agent(str(tmp_path))
    with pytest.raises(ConfigError, match="unknown agent 'nobody'"):
        make_agent("nobody")


def test_a_training_folder_and_its_zip_resolve_to_the_model_that_ran(tiny_learner):
    """The tiny learner of this pytest run, by its folder and by its file: one agent that
    records what ran and drives behind the stack it was trained with."""
    folder, summary = tiny_learner
    by_folder, by_file = make_agent(str(folder)), make_agent(str(folder / "model.zip"))
    assert by_folder.digest == by_file.digest
    assert by_folder.trained_on()["algo"] == summary["algo"] == "dagger+ppo"
    env = by_folder.make_env()
    try:
        obs, _ = env.reset(seed=0)
        by_folder.begin(env)
        action = by_folder.act(obs)
        assert env.action_space.contains(action)
    finally:
        env.close()


def test_a_fine_tuned_folders_clones_are_an_agent_of_their_own(tiny_learner, tmp_path):
    """``clone:FOLDER`` is the policy each reward stage started from: its own row and group,
    named beside the fine-tuned model; a folder whose runs kept no clone is refused by name."""
    folder, _ = tiny_learner
    (clone,) = resolve_agent(f"clone:{folder}")
    assert clone == str((folder / "finetune" / "clone.zip").resolve())
    assert make_agent(clone).digest != make_agent(str(folder)).digest
    assert make_agent(clone).trained_on()["algo"] == "dagger"  # what ran before the reward stage
    assert make_agent(str(folder)).trained_on()["algo"] == "dagger+ppo"
    (model,) = expand_agents([str(folder)])
    assert agent_name(clone) == f"{agent_name(model)} clone"
    assert training_group(clone) == f"clone:{training_group(model)}"
    assert agent_name(training_group(clone)) == f"{agent_name(training_group(model))} clone"
    run = tmp_path / "cloned" / "seed-0"
    run.mkdir(parents=True)
    (run / "model.zip").write_bytes(pretrained.models(SHIPPED)[0].read_bytes())
    with pytest.raises(ConfigError, match=r"seed-0/finetune/clone.zip not found"):
        resolve_agent(f"clone:{run.parent}")


def test_models_under_the_working_directory_are_named_relative_to_it(tiny_learner, monkeypatch):
    """A run started at a clone's root names its models relative to it: its cells and results
    carry no path of the machine, and the same run from another clone reuses them."""
    folder, _ = tiny_learner
    outside = resolve_agent(f"clone:{folder}")
    assert Path(outside[0]).is_absolute()
    monkeypatch.chdir(folder.parent)
    relative = [f"{folder.name}/finetune/clone.zip"]
    assert resolve_agent(f"clone:{folder}") == relative == resolve_agent(f"clone:{folder.name}")
    assert resolve_agent(str(folder)) == [f"{folder.name}/model.zip"]
    assert make_agent(relative[0]).digest == make_agent(outside[0]).digest
    assert training_group(relative[0]) == f"clone:{folder.name}"


def test_the_benchmark_expands_names_with_the_same_resolver():
    names = [SHIPPED, "follower", str(pretrained.models(EKF_AGENT)[0])]
    assert expand_agents(names) == [m for n in names for m in resolve_agent(n)]


@pytest.mark.parametrize(
    ("record", "algo"),
    [
        (
            {"algo": "ppo", "demonstrations": {"rounds": 4}, "hyperparams": {"n_timesteps": 0}},
            "dagger",
        ),
        (
            {"algo": "ppo", "demonstrations": {"rounds": 4}, "hyperparams": {"n_timesteps": 9}},
            "dagger+ppo",
        ),
        ({"algo": "ppo", "demonstrations": None, "hyperparams": {"n_timesteps": 9}}, "ppo"),
        ({"algo": "dagger+ppo", "demonstrations": {"rounds": 4}}, "dagger+ppo"),
        ({"algo": "dagger"}, "dagger"),
    ],
)
def test_the_algorithm_is_read_as_what_ran(record, algo):
    assert trained_algo(record) == algo


def test_a_shipped_agent_builds_the_env_it_was_trained_for():
    agent = make_agent(EKF_AGENT)
    env = agent.make_env(sim__max_episode_seconds=3.0)
    try:
        meta = agent.meta
        assert isinstance(env, DecisionInterval) and env.steps == meta["decision_steps"]
        policy = env.env
        assert policy.config == observation_config(meta["observation"])
        assert "stop" in env.get_wrapper_attr("action_layout")
        obs, _ = env.reset(seed=0)
        obs, *_ = env.step(agent.act(obs))
        assert obs.shape == agent.model.observation_space.shape
    finally:
        env.close()


def _estimating(make_env, **overrides):
    return make_env("stsf_gym/Suite-Corridor-Truth-v0", camera__enabled=False, **overrides)


def test_an_env_unlike_the_models_settings_is_refused(make_env):
    model = pretrained.models(EKF_AGENT)[0]
    with pytest.raises(ConfigError, match="drives on a pose estimate"):
        wrap_for_model(make_env("stsf_gym/Straight10m-v0", camera__enabled=False), model)
    with pytest.raises(ConfigError, match="task__stop_action=True"):
        wrap_for_model(_estimating(make_env, task__stop_action=False), model)
    with pytest.raises(ConfigError, match=r"sim\.control_dt"):
        wrap_for_model(_estimating(make_env, task__stop_action=True, sim__control_dt=0.2), model)
    env = _estimating(make_env, task__stop_action=True)
    other = PolicyObservation(env, observation_config({"far_goal": "direction"}))
    with pytest.raises(ConfigError, match="policy observation"):
        wrap_for_model(other, model)
    meta_observation = SB3Agent(str(model)).meta["observation"]
    held = DecisionInterval(PolicyObservation(env, observation_config(meta_observation)), 2)
    with pytest.raises(ConfigError, match="decision_steps"):
        wrap_for_model(held, model)
    stack = wrap_for_model(env, model)
    assert wrap_for_model(stack, model) is stack  # already as the model expects


def test_a_stop_agent_makes_every_row_judged_by_the_declare_protocol():
    env = judged_alike([SHIPPED, "follower"], ["truth"], {"sim": {"max_episode_seconds": 3.0}})
    assert env["task"]["protocol"] == "declare" and env["sim"]["max_episode_seconds"] == 3.0
    assert judged_alike(["follower"], ["truth"], {}) == {}


def test_each_model_is_its_own_row_and_its_seeds_are_aggregated():
    models = [str(m) for m in pretrained.models(SHIPPED)]
    assert [agent_name(m) for m in models] == [f"dagger-truth/seed-{s}" for s in (0, 1, 2)]

    def episodes(successes):
        return [
            SimpleNamespace(spec={"seed": s}, outcome="goal" if ok else "time")
            for s, ok in enumerate(successes)
        ]

    by_pair = {
        (models[0], "truth"): episodes([1, 1, 0, 1]),
        (models[1], "truth"): episodes([1, 0, 0, 1]),
        (models[2], "truth"): episodes([1, 1, 1, 1]),
        ("follower", "truth"): episodes([1, 1, 1, 1]),
    }
    (row,) = seed_aggregates(by_pair)
    assert row["agent"] == SHIPPED and row["runs"] == 3 and row["episodes"] == 4
    assert row["success_per_run"] == [0.75, 0.5, 1.0]
    assert row["success_iqm_ci95"][0] <= row["success_iqm"] <= row["success_iqm_ci95"][1]


@pytest.mark.slow
def test_evaluate_prints_a_row_per_model_and_the_seeds_together(tmp_path):
    from stsf_gym.cli import main

    argv = f"evaluate --agent {SHIPPED},follower --estimators truth --seeds 1 --workers 1"
    argv += " --set sim.max_episode_seconds=3 --set camera.enabled=false --json"
    assert main([*argv.split(), "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "comparison.json").read_text())
    agents = [r["agent"] for r in summary["rows"]]
    assert agents == [*map(model_path, pretrained.models(SHIPPED)), "follower"]
    assert [a["agent"] for a in summary["aggregates"]] == [SHIPPED]
    assert "dagger-truth/seed-2" in (Path(tmp_path) / "comparison.md").read_text()


def test_a_stop_entry_on_the_reach_protocol_names_its_key_once_with_what_to_set():
    from stsf_gym.envs.config import load_config

    with pytest.raises(ConfigError) as caught:
        load_config(world="straight_10m", task={"stop_action": True})
    message = str(caught.value)
    assert "task.task." not in message and message.count("task.protocol is 'reach'") == 1
    assert "--set task.protocol=declare" in message
