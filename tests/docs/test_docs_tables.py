"""The docs' id and shipped-agent tables are the registries' (``benchmarks/docs_tables.py``)."""

import importlib.util
import sys

import gymnasium as gym
from helpers import ROOT

SPEC = importlib.util.spec_from_file_location("docs_tables", ROOT / "benchmarks" / "docs_tables.py")
tables = sys.modules["docs_tables"] = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(tables)


def test_every_generated_table_is_current():
    assert not tables.stale(), "run python benchmarks/docs_tables.py --write"


def test_the_id_table_names_every_registered_id():
    text = tables.id_table()
    rows = [line.split(" | ") for line in text.splitlines()[2:] if line.startswith("| ")]
    listed = set()
    for family, raw, sources in rows:
        listed |= {raw.strip("` ")} - {"-"}
        for source in sources.rstrip(" |").split(", "):
            listed.add(f"stsf_gym/{family.strip('| ')}-{source.strip('`')}-v0")
    assert listed == {i for i in gym.registry if i.startswith("stsf_gym/")}


def test_the_agent_table_lists_every_shipped_agent():
    from stsf_gym.agents import pretrained

    text = tables.agents_table()
    for agent in pretrained.listing():
        assert f"| `{agent['name']}`" in text
    assert "`pretrained:sparse/dagger+ppo-stsf` | the DAgger clone, then PPO" in text


def test_the_reward_paragraph_names_every_term():
    from dataclasses import fields

    from stsf_gym.envs.config import RewardConfig

    page = (ROOT / "docs" / "environment" / "index.md").read_text()
    paragraph = page[page.index("**Reward**") :].split("\n\n")[0]
    for term in fields(RewardConfig):
        assert f"`reward.{term.name}`" in paragraph, term.name
