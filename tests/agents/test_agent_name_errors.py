"""Agent names that make no agent, refused naming what is missing: an object that is not an
agent, a module, an empty name, a symlink loop as a model, and an alias named beside its shipped
name."""

from __future__ import annotations

import re

import pytest

from stsf_gym.validation import ConfigError


@pytest.mark.parametrize(
    ("name", "said"),
    [
        (
            "json:JSONDecoder",
            "made a JSONDecoder, which is not an agent: it lacks wrap, begin, act",
        ),
        ("builtins:print", "made a NoneType, which is not an agent: it lacks wrap"),
        ("os:path", "agent 'os:path' is a module, not an agent class"),
        ("json:loads", "agent 'json:loads' cannot be made with no options: missing a required"),
        (
            "stsf_gym.agents.registry:Agent",
            "agent 'stsf_gym.agents.registry:Agent' is a protocol (an interface), not an agent",
        ),
        ("", "an agent name may not be empty, got ''"),
        (" ", "an agent name may not be empty, got ' '"),
    ],
)
def test_a_name_that_makes_no_agent_is_refused_naming_what_is_missing(name, said):
    from stsf_gym.agents.registry import make_agent

    with pytest.raises(ConfigError, match=re.escape(said)):
        make_agent(name)


def test_options_a_class_does_not_take_are_named_before_it_is_called():
    from stsf_gym.agents.registry import make_agent

    name = "stsf_gym.agents.trained_agent:SB3Agent"  # SB3Agent(path): no model is loaded
    with pytest.raises(ConfigError, match=r"options \['gian', 'path'\]: got an unexpected keyword"):
        make_agent(name, {"path": "model.zip", "gian": 1.0})


def test_an_object_that_is_not_an_agent_is_refused_on_the_command_line(run_cli, tmp_path):
    code, err = run_cli("evaluate", "--agent", "json:JSONDecoder", "--out", str(tmp_path / "o"))
    assert code == 2 and len(err.strip().splitlines()) == 1 and "not an agent" in err
    assert not (tmp_path / "o").exists()


def test_a_symlink_loop_as_a_model_is_refused(tmp_path):
    from stsf_gym.agents.registry import make_agent

    (tmp_path / "a.zip").symlink_to(tmp_path / "b.zip")
    (tmp_path / "b.zip").symlink_to(tmp_path / "a.zip")
    with pytest.raises(ConfigError, match=r"a\.zip cannot be followed"):
        make_agent(str(tmp_path / "a.zip"))


def test_an_alias_and_its_shipped_name_are_one_agent_named_twice():
    from stsf_gym.experiments.benchmark.trained import expand_agents

    alias, canonical = "pretrained:corridor/ppo-truth", "pretrained:corridor/dagger-truth"
    with pytest.raises(ConfigError, match=f"{alias!r} and {canonical!r} name the same agent"):
        expand_agents(["follower", alias, canonical])
    assert expand_agents(["follower", canonical]) == ["follower", *expand_agents([alias])]
