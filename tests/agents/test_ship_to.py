"""Shipping into a folder the user names (``--ship-to DIR``), never into the installed package:
the package's shipped agents keep their bytes, the shipped folder is read by its manifest, an
edited model is refused in one line naming it, and bad input is refused before any file is
written."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers import training_folder as shared_training_folder

from stsf_gym.agents import pretrained
from stsf_gym.agents.pretrained import shipping
from stsf_gym.agents.pretrained.shipped_folder import MANIFEST, manifest, manifest_of
from stsf_gym.agents.registry import make_agents
from stsf_gym.agents.resolve import resolve_agent, training_group
from stsf_gym.experiments.benchmark.trained import agent_name
from stsf_gym.validation import ConfigError

SOURCE = pretrained.MODELS / "corridor" / "dagger-truth"  # 3 seeds, trained on the corridor suite
STSF = pretrained.MODELS / "corridor" / "dagger-stsf"  # seed 0, the same suite on STSF


def training_folder(root: Path, seeds=(0,), source: Path = SOURCE) -> Path:
    """A `train --seeds N` folder holding ``source``'s models of ``seeds``."""
    return shared_training_folder(root, seeds, source)


def package_files() -> dict[str, str]:
    """The digest of every file of the package's shipped agents, and its manifest's text."""
    listed = (pretrained.MODELS / MANIFEST).read_text()
    return {**manifest_of(pretrained.MODELS)["files"], MANIFEST: listed}


@pytest.mark.slow
def test_a_ship_writes_to_the_named_folder_and_is_read_back_by_its_manifest(tmp_path, run_cli):
    before = package_files()
    to = tmp_path / "mine"  # made by the ship
    argv = ["--ship", str(training_folder(tmp_path / "t", (0, 1))), "--suite", "corridor"]
    code, err = run_cli("agents", *argv, "--ship-to", str(to))
    assert code == 0, err
    agent = to / "corridor" / "dagger-truth"
    assert manifest(to) == manifest_of(to)["files"] and len(manifest(to)) == 5
    assert package_files() == before  # the package only read
    models = resolve_agent(str(agent))
    assert [Path(m).name for m in models] == ["seed-0.zip", "seed-1.zip"]
    assert all(Path(m).resolve().parent == agent.resolve() for m in models)
    assert len(make_agents(str(agent))) == 2
    assert {training_group(m) for m in models} == {str(Path(models[0]).parent)}
    assert agent_name(models[1]) == "dagger-truth/seed-1"
    assert json.loads((agent / "agent.json").read_text())["name"] == "corridor/dagger-truth"


def test_an_edited_model_in_a_shipped_folder_is_refused_in_one_line(tmp_path, run_cli):
    to = tmp_path / "mine"
    ship = ["agents", "--ship", str(training_folder(tmp_path / "t")), "--suite", "corridor"]
    assert run_cli(*ship, "--ship-to", str(to))[0] == 0
    model = to / "corridor" / "dagger-truth" / "seed-0.zip"
    model.write_bytes(model.read_bytes() + b"\0")
    with pytest.raises(ConfigError, match=r"seed-0\.zip: its bytes are not those .* lists"):
        resolve_agent(str(model.parent))
    out = tmp_path / "out"
    argv = ["--suite", "corridor", "--agents", str(model.parent), "--out", str(out)]
    code, err = run_cli("benchmark", *argv)
    assert code == 2 and f"{model}: its bytes are not those" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.slow
def test_a_replacing_ship_keeps_the_digests_listed_for_its_neighbours(tmp_path, run_cli):
    """A file edited by hand beside the agent shipped again is not blessed by the new manifest."""
    to = tmp_path / "mine"
    truth = ["agents", "--ship-to", str(to), "--suite", "corridor", "--ship"]
    assert run_cli(*truth, str(training_folder(tmp_path / "a")))[0] == 0
    assert run_cli(*truth, str(training_folder(tmp_path / "s", (0,), STSF)))[0] == 0
    edited = to / "corridor" / "dagger-stsf" / "seed-0.zip"
    edited.write_bytes(edited.read_bytes() + b"\0")
    assert run_cli(*truth, str(training_folder(tmp_path / "b", (2,))), "--replace")[0] == 0
    assert [Path(m).name for m in resolve_agent(str(to / "corridor" / "dagger-truth"))] == [
        "seed-2.zip"
    ]
    with pytest.raises(ConfigError, match="not those"):
        resolve_agent(str(edited.parent))


def test_a_ship_needs_a_folder_named_and_writes_nothing_without(tmp_path, run_cli):
    training = training_folder(tmp_path / "t")
    before = package_files()
    code, err = run_cli("agents", "--ship", str(training), "--suite", "corridor")
    assert code == 2 and "--ship needs --ship-to DIR" in err
    code, err = run_cli("agents", "--ship-to", str(tmp_path / "x"))
    assert code == 2 and "--ship-to is where --ship puts a shipped agent" in err
    assert package_files() == before and not (tmp_path / "x").exists()


def test_a_ship_into_the_installed_package_is_refused(tmp_path, run_cli, monkeypatch):
    """Outside a git checkout (a wheel) the package's folders are only read."""
    monkeypatch.setattr(shipping, "from_checkout", lambda: False)
    before = package_files()
    training = training_folder(tmp_path / "t")
    for to in (pretrained.MODELS, pretrained.MODELS / "mine"):
        argv = ["--ship", str(training), "--suite", "corridor", "--ship-to", str(to)]
        code, err = run_cli("agents", *argv, "--replace")
        assert code == 2 and f"--ship-to {to}: inside the installed package" in err
    assert package_files() == before and not (pretrained.MODELS / "mine").exists()
