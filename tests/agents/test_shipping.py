"""Shipping and naming trained agents: a ship is checked whole before the folder it ships to
(``--ship-to``) changes, then swapped in at once; a training folder is scored or shipped whole
or not at all; a shipped name never reaches outside the shipped folder; corrupt weights fail
the pre-flight check.

The training folders here are made of a shipped agent's own files (its models and their
``train.json``), so every check meets real models and real metadata."""

from __future__ import annotations

import json
import shutil
import zipfile
from pathlib import Path

import pytest
from helpers import training_folder as shared_training_folder

from stsf_gym.agents import pretrained
from stsf_gym.validation import ConfigError

SOURCE = pretrained.MODELS / "corridor" / "dagger-truth"  # 3 seeds, trained on the corridor suite
STSF = pretrained.MODELS / "corridor" / "dagger-stsf"  # seed 0, the same suite on STSF


def training_folder(root: Path, seeds=(0, 1), source: Path = SOURCE) -> Path:
    """A `train --seeds N` folder holding ``source``'s models of ``seeds``."""
    return shared_training_folder(root, seeds, source)


def ship(run_cli, models: Path, training: Path, *extra: str) -> tuple[int, str]:
    """``stsf-gym agents --ship-to MODELS --ship TRAINING --suite corridor EXTRA...``."""
    return run_cli(
        "agents", "--ship-to", str(models), "--ship", str(training), "--suite", "corridor", *extra
    )


@pytest.fixture
def models(tmp_path) -> Path:
    """An empty folder of the user's to ship into (``--ship-to``)."""
    folder = tmp_path / "shipped-agents"
    folder.mkdir()
    return folder


def shipped_files(models: Path) -> dict[str, bytes]:
    """Every file under ``models`` by relative path, with its bytes."""
    return {str(p.relative_to(models)): p.read_bytes() for p in models.rglob("*") if p.is_file()}


def test_a_ship_writes_the_agent_whole_and_its_listing(models, tmp_path, run_cli):
    code, err = ship(run_cli, models, training_folder(tmp_path / "t"))
    assert code == 0, err
    record = json.loads((models / "corridor" / "dagger-truth" / "agent.json").read_text())
    assert record["seeds"] == [0, 1] and set(record["seen"]) == {"0", "1"}
    assert sorted(p.name for p in (models / "corridor").iterdir()) == ["dagger-truth"]  # no temp


def test_a_ship_over_a_shipped_name_is_refused_without_replace(models, tmp_path, run_cli):
    assert ship(run_cli, models, training_folder(tmp_path / "a"))[0] == 0
    before = shipped_files(models)
    code, err = ship(run_cli, models, training_folder(tmp_path / "b", (2,)))
    assert code == 2 and "already shipped as corridor/dagger-truth" in err and "--replace" in err
    assert shipped_files(models) == before


def test_a_replacing_ship_leaves_no_orphan_seeds(models, tmp_path, run_cli):
    ship(run_cli, models, training_folder(tmp_path / "a", (0, 1)))
    argv = [
        "--ship-to",
        str(models),
        "--ship",
        str(training_folder(tmp_path / "b", (2,))),
        "--suite",
        "corridor",
        "--replace",
    ]
    code, err = run_cli("agents", *argv)
    assert code == 0, err
    folder = models / "corridor" / "dagger-truth"
    assert sorted(p.name for p in folder.iterdir()) == ["agent.json", "seed-2.json", "seed-2.zip"]
    assert json.loads((folder / "agent.json").read_text())["seeds"] == [2]


def test_a_ship_failing_part_way_leaves_the_shipped_agent_as_it_was(
    models, tmp_path, run_cli, monkeypatch
):
    """The second seed's seen inputs fail (as an unreadable model would): nothing changes."""
    ship(run_cli, models, training_folder(tmp_path / "a", (0, 1)))
    before = shipped_files(models)
    real, calls = pretrained.seen_inputs, []

    def failing(model, suite, source, recorded=None):
        calls.append(model)
        if len(calls) == 2:
            raise OSError("disk gone")
        return real(model, suite, source, recorded)

    monkeypatch.setattr(pretrained, "seen_inputs", failing)
    argv = [
        "--ship-to",
        str(models),
        "--ship",
        str(training_folder(tmp_path / "b", (1, 2))),
        "--suite",
        "corridor",
        "--replace",
    ]
    with pytest.raises(OSError, match="disk gone"):
        run_cli("agents", *argv)
    assert shipped_files(models) == before
    assert sorted(p.name for p in (models / "corridor").iterdir()) == ["dagger-truth"]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        ({"estimator": "stsf"}, "train.json says estimator 'stsf', its model 'truth'"),
        ({"suite": "sparse"}, "train.json says suite 'sparse', its model 'corridor'"),
        ({"algo": "sac"}, "train.json says algo 'sac', its model 'ppo'"),
        ({"made_by": {"code": "0", "config": "0"}}, "train.json says made_by"),
    ],
)
def test_an_edited_train_json_is_refused(models, tmp_path, run_cli, edit, message):
    folder = training_folder(tmp_path / "t")
    record = folder / "seed-1" / "train.json"
    record.write_text(json.dumps({**json.loads(record.read_text()), **edit}))
    code, err = run_cli(
        "agents", "--ship-to", str(models), "--ship", str(folder), "--suite", "corridor"
    )
    assert code == 2 and message in err and "seed-1" in err
    assert shipped_files(models) == {}


def test_a_ship_under_another_suite_is_refused(models, tmp_path, run_cli):
    code, err = run_cli(
        "agents",
        "--ship-to",
        str(models),
        "--ship",
        str(training_folder(tmp_path / "t")),
        "--suite",
        "sparse",
    )
    assert code == 2 and "trained on suite 'corridor', not --suite 'sparse'" in err
    assert shipped_files(models) == {}


def test_seeds_of_two_pose_sources_do_not_ship_as_one_agent(models, tmp_path, run_cli):
    folder = training_folder(tmp_path / "t", (0,), STSF)
    training_folder(folder, (1,))  # the true pose's seed 1 beside STSF's seed 0
    code, err = run_cli(
        "agents", "--ship-to", str(models), "--ship", str(folder), "--suite", "corridor"
    )
    assert code == 2 and "seed 1 has estimator 'truth', seed 0 'stsf'" in err
    assert shipped_files(models) == {}


def test_an_unreadable_model_is_refused_before_anything_is_shipped(models, tmp_path, run_cli):
    folder = training_folder(tmp_path / "t")
    corrupt_weights(folder / "seed-1" / "model.zip")
    code, err = run_cli(
        "agents", "--ship-to", str(models), "--ship", str(folder), "--suite", "corridor"
    )
    assert code == 2 and "policy.pth) cannot be read" in err and "weights_only" not in err
    assert shipped_files(models) == {}


def test_a_read_only_destination_fails_in_one_line(models, tmp_path, run_cli, monkeypatch):
    import stsf_gym.agents.pretrained.shipping as shipping

    def refused(folder, flag):
        raise PermissionError(f"{flag} {folder}: not writable (Read-only file system)")

    monkeypatch.setattr(shipping, "check_folder", refused)
    code, err = ship(run_cli, models, training_folder(tmp_path / "t"))
    assert code == 2 and "the shipping destination" in err and "Traceback" not in err
    assert shipped_files(models) == {}


def corrupt_weights(model: Path) -> None:
    """Rewrite ``model``'s ``policy.pth`` as bytes torch cannot load; the zip stays valid."""
    with zipfile.ZipFile(model) as archive:
        entries = {name: archive.read(name) for name in archive.namelist()}
    entries["policy.pth"] = b"PK\x03\x04 not the tensors" + entries["policy.pth"][:40]
    with zipfile.ZipFile(model, "w") as archive:
        for name, data in entries.items():
            archive.writestr(name, data)


def test_corrupt_weights_fail_the_pre_flight_check_in_one_line(tmp_path, run_cli):
    folder = training_folder(tmp_path / "t", (0,))
    corrupt_weights(folder / "seed-0" / "model.zip")
    out = tmp_path / "out"
    code, err = run_cli(
        "benchmark",
        "--suite",
        "corridor",
        "--agents",
        str(folder),
        "--worlds",
        "1",
        "--out",
        str(out),
    )
    assert code == 2 and "policy.pth) cannot be read" in err and "weights_only" not in err
    assert not (out / "corridor").exists()


@pytest.mark.parametrize("command", ["benchmark", "accuracy-curve"])
def test_an_unfinished_seed_is_named_not_left_out(tmp_path, run_cli, command):
    folder = training_folder(tmp_path / "t", (0,))
    (folder / "seed-1" / "checkpoints").mkdir(parents=True)  # a run under way: no model.zip yet
    flag = "--agents" if command == "benchmark" else "--agent"
    code, err = run_cli(
        command, "--suite", "corridor", flag, str(folder), "--out", str(tmp_path / "o")
    )
    assert code == 2 and "seed-1: an unfinished training run (no model.zip)" in err
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").rglob("*.json"))


def test_a_misnamed_seed_folder_is_named(models, tmp_path, run_cli):
    folder = training_folder(tmp_path / "t", (0,))
    (folder / "seed-abc").mkdir()
    for argv in (
        ["agents", "--ship-to", str(models), "--ship", str(folder), "--suite", "corridor"],
        ["benchmark", "--suite", "corridor", "--agents", str(folder), "--out", str(tmp_path / "o")],
    ):
        code, err = run_cli(*argv)
        assert code == 2 and "seed-abc: not a training seed's folder" in err, argv
    assert shipped_files(models) == {}


@pytest.mark.parametrize(
    "name",
    [
        "pretrained:../x",
        "pretrained:corridor/../ppo-truth",
        "pretrained:./ppo-truth",
        "pretrained:.x/y",
    ],
)
def test_a_shipped_name_never_reaches_outside_the_shipped_folder(tmp_path, name, monkeypatch):
    """An agent planted beside the shipped folder, where ``../x`` would name it."""
    models = tmp_path / "trained-models"
    (models / "corridor").mkdir(parents=True)
    (tmp_path / "x").mkdir()
    (tmp_path / "x" / "agent.json").write_text(json.dumps({"seeds": []}))
    monkeypatch.setattr(pretrained, "MODELS", models)
    with pytest.raises(ConfigError, match="no shipped agent"):
        pretrained.folder(name)


def test_agents_suite_lists_that_suites_agents_only(capsys, monkeypatch):
    import stsf_gym.cli as cli

    monkeypatch.setattr(cli, "_silence_c_stdout", lambda: None)
    assert cli.main(["agents", "--suite", "corridor", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert rows and {r["suite"] for r in rows} == {"corridor"}
    assert cli.main(["agents", "--replace"]) == 2
    assert "--replace replaces a shipped agent by --ship" in capsys.readouterr().err


def test_a_shipped_agents_folder_is_readable_as_any_other(models, tmp_path, run_cli):
    """Built beside its destination, it keeps the mode ``mkdir`` gives (not mkdtemp's 0o700)."""
    import os

    umask = os.umask(0o022)
    try:
        assert ship(run_cli, models, training_folder(tmp_path / "t", (0,)))[0] == 0
    finally:
        os.umask(umask)
    assert (models / "corridor" / "dagger-truth").stat().st_mode & 0o777 == 0o755


def test_a_fine_tuned_agent_ships_without_optimizer_moments_and_with_its_own_val_success(
    models, tmp_path, run_cli, tiny_learner
):
    """The reward stage's Adam moments are twice the weights and acting reads none of them;
    the listing's val success is the fine-tuned model's, not its clone's."""
    import numpy as np

    from stsf_gym.agents.model_files import load_model

    folder, summary = tiny_learner
    record = json.loads((folder / "train.json").read_text())
    run = tmp_path / "fine" / f"seed-{record['seed']}"
    run.mkdir(parents=True)
    shutil.copyfile(folder / "model.zip", run / "model.zip")
    shutil.copyfile(folder / "train.json", run / "train.json")
    code, err = run_cli(
        "agents", "--ship-to", str(models), "--ship", str(run.parent), "--suite", "corridor"
    )
    assert code == 0, err
    (shipped,) = (models / "corridor").glob("dagger+ppo-*/seed-*.zip")
    assert shipped.stat().st_size < 0.6 * (run / "model.zip").stat().st_size
    original, lean = load_model(run / "model.zip"), load_model(shipped)
    obs = original.observation_space.sample()
    assert np.array_equal(
        original.predict(obs, deterministic=True)[0], lean.predict(obs, deterministic=True)[0]
    )
    assert (
        lean.policy.optimizer.param_groups[0]["lr"]
        == original.policy.optimizer.param_groups[0]["lr"]
    )
    with zipfile.ZipFile(shipped) as lean_zip, zipfile.ZipFile(run / "model.zip") as whole:
        assert sorted(lean_zip.namelist()) == sorted(whole.namelist())
    listed = json.loads((shipped.parent / "agent.json").read_text())["val_success"]
    last = summary["last_evaluation"]
    assert last["timesteps"] > 0 and listed == {str(record["seed"]): last["success_rate"]}
