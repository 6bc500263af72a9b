"""Commands that would lose work, ignore an option or fail late, refused in one line before any
work: training onto another run, conflicting or meaningless options, seeds out of range, Ray
addresses nobody answers, another benchmark's folder, an empty config, an unwritable --out,
a baseline that is no checkout; and a cell file cut short is redone."""

from __future__ import annotations

import json
import shutil
import socket
from pathlib import Path

import pytest

from stsf_gym.agents import pretrained
from stsf_gym.experiments.jobs.cells import cell_name
from stsf_gym.experiments.jobs.engine import forget_failures
from stsf_gym.experiments.jobs.store import open_store, read_rows, write_row
from stsf_gym.validation import ConfigError

SHIPPED = pretrained.MODELS / "corridor" / "dagger-truth"  # trained on the corridor suite, truth


def finished_run(out: Path, with_record: bool = True) -> dict[str, bytes]:
    """``out`` holding a finished run (a shipped seed's model and train.json); its files."""
    out.mkdir(parents=True)
    shutil.copyfile(SHIPPED / "seed-0.zip", out / "model.zip")
    if with_record:
        shutil.copyfile(SHIPPED / "seed-0.json", out / "train.json")
    return {p.name: p.read_bytes() for p in out.iterdir()}


def files(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in out.iterdir()}


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["--suite", "corridor", "--estimator", "odometry"], "estimator 'truth' (not 'odometry')"),
        (["--suite", "sparse"], "suite 'corridor' (not 'sparse')"),
        (["--world", "straight_10m"], "world 'generated:train' (not 'straight_10m')"),
    ],
)
@pytest.mark.parametrize("with_record", [True, False])
def test_train_onto_another_finished_run_is_refused(run_cli, tmp_path, argv, said, with_record):
    out = tmp_path / "run"
    before = finished_run(out, with_record)
    code, err = run_cli("train", *argv, "--out", str(out))
    assert code == 2 and "holds another training run" in err and said in err
    assert files(out) == before


def test_a_campaign_onto_another_runs_folder_is_refused(run_cli, tmp_path):
    before = finished_run(tmp_path / "c" / "truth" / "seed-0")
    code, err = run_cli(
        "train", "--suite", "sparse", "--estimators", "truth", "--out", str(tmp_path / "c")
    )
    assert code == 2 and "suite 'corridor' (not 'sparse')" in err
    assert files(tmp_path / "c" / "truth" / "seed-0") == before


def test_a_checkpoint_alone_marks_the_folder_as_another_runs(run_cli, tmp_path):
    out = tmp_path / "run"
    (out / "checkpoints").mkdir(parents=True)
    shutil.copyfile(SHIPPED / "seed-0.zip", out / "checkpoints" / "model_512_steps.zip")
    code, err = run_cli("train", "--suite", "corridor", "--estimator", "ekf", "--out", str(out))
    assert code == 2 and "model_512_steps.zip" in err and "estimator 'truth'" in err


def test_estimator_and_estimators_together_are_refused(run_cli, tmp_path):
    code, err = run_cli(
        "train", "--estimator", "stsf", "--estimators", "ekf", "--out", str(tmp_path / "o")
    )
    assert code == 2 and "--estimator names one run's pose source" in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(("seed", "seeds"), [(2**32, 1), (2**32 - 2, 3)])
def test_a_training_seed_out_of_range_is_refused_before_any_file(run_cli, tmp_path, seed, seeds):
    argv = ["--seed", str(seed), "--seeds", str(seeds), "--out", str(tmp_path / "o")]
    code, err = run_cli("train", *argv)
    assert code == 2 and f"training seeds must lie in 0..{2**32 - 1}" in err
    assert not (tmp_path / "o").exists()


def test_address_on_a_local_campaign_is_refused(run_cli, tmp_path):
    argv = ["--estimators", "truth", "--address", "head:6379", "--out", str(tmp_path / "o")]
    code, err = run_cli("train", *argv)
    assert code == 2 and "--address is only for --backend ray" in err
    assert not (tmp_path / "o").exists()


def closed_port() -> int:
    """A local TCP port nothing listens on."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.mark.parametrize(
    "argv",
    [
        ["train", "--estimators", "truth", "--backend", "ray"],
        ["benchmark", "--suite", "corridor", "--worlds", "1", "--backend", "ray"],
    ],
)
def test_an_unreachable_ray_address_fails_at_once(run_cli, tmp_path, argv):
    address = f"127.0.0.1:{closed_port()}"
    code, err = run_cli(*argv, "--address", address, "--out", str(tmp_path / "o"))
    assert code == 2 and f"--address {address}: nothing answers there" in err


def test_a_failed_cell_is_forgotten_and_a_store_that_is_no_store_set_aside(tmp_path, capsys):
    """A failed cell's row is deleted, so the rerun redoes it; a finished cell's row stays.
    A file under the store's name that is not SQLite is set aside, not raised."""
    cells = [
        {"kind": "evaluate", "estimator": e, "seed": 0, "values": {"estimator": e}}
        for e in ("stsf", "mcl")
    ]
    store = tmp_path / "cells.sqlite"
    store.write_text('{"job": {"kind": "eval')  # a cell file of old, cut short
    open_store(store)
    assert "not a readable store" in capsys.readouterr().err
    assert (tmp_path / "cells.sqlite.unreadable").is_file()
    failed, finished = cells
    write_row(store, cell_name(failed), failed, "c", {"m.py": "1"}, {"error": "RuntimeError"})
    write_row(store, cell_name(finished), finished, "c", {"m.py": "1"}, {"metrics": {}})
    forget_failures(cells, store, cell_name)
    assert list(read_rows(store)) == [cell_name(finished)]


def test_another_benchmark_into_a_reports_folder_is_refused(run_cli, tmp_path):
    report = tmp_path / "out" / "corridor" / "results.json"
    report.parent.mkdir(parents=True)
    request = {"agents": ["follower"], "estimators": None, "worlds": 3, "seed": 0}
    report.write_text(json.dumps({"request": request, "rows": []}))
    code, err = run_cli(
        "benchmark", "--suite", "corridor", "--worlds", "2", "--out", str(tmp_path / "out")
    )
    assert code == 2 and "holds the report of another benchmark (worlds 3 there, 2 now)" in err
    assert json.loads(report.read_text())["request"] == request
    assert sorted(p.name for p in report.parent.iterdir()) == ["results.json"]
    code, err = run_cli(
        "benchmark", "--suite", "corridor", "--worlds", "4", "--agents", "cautious-follower",
        "--out", str(tmp_path / "out"),
    )  # fmt: skip
    assert code == 2 and "agents ['follower'] there, ['cautious-follower'] now" in err


def test_a_benchmark_on_more_worlds_or_agents_extends_the_report_of_fewer(tmp_path):
    """A long run reported on the worlds it has finished, then on all of them; agents trained
    later added beside the earlier ones. Leaving out a world or an agent is refused."""
    from stsf_gym.experiments.benchmark.run import check_same_request

    report = tmp_path / "results.json"
    fewer = {"agents": ["follower"], "estimators": ["truth"], "worlds": 40, "seed": 0}
    report.write_text(json.dumps({"request": fewer, "rows": []}))
    check_same_request(report, {**fewer, "worlds": 100})  # extends it: allowed
    check_same_request(report, {**fewer, "agents": ["follower", "cautious-follower"]})
    with pytest.raises(ConfigError, match="estimators \\['truth'\\] there, None now"):
        check_same_request(report, {**fewer, "worlds": 100, "estimators": None})
    report.write_text(json.dumps({"request": {**fewer, "worlds": 100}, "rows": []}))
    with pytest.raises(ConfigError, match="worlds 100 there, 40 now"):
        check_same_request(report, fewer)
    more = {**fewer, "agents": ["follower", "cautious-follower"], "worlds": 100}
    report.write_text(json.dumps({"request": more, "rows": []}))
    with pytest.raises(ConfigError, match="agents \\['follower', 'cautious-follower'\\] there"):
        check_same_request(report, {**more, "agents": ["cautious-follower"]})


def test_a_dial_scale_is_named_as_the_levels(run_cli, tmp_path):
    code, err = run_cli("accuracy-curve", "--dial", "scale=2", "--out", str(tmp_path / "o"))
    assert code == 2 and "--dial scale=2: the dial's scale is what --levels lists" in err


@pytest.mark.parametrize("text", ["", "# only a comment\n"])
def test_an_empty_config_file_is_refused(run_cli, tmp_path, text):
    config = tmp_path / "empty.yaml"
    config.write_text(text)
    code, err = run_cli("evaluate", "--config", str(config), "--out", str(tmp_path / "o"))
    assert code == 2 and "the file is empty, it sets nothing" in err
    assert not (tmp_path / "o").exists()


def test_an_out_under_a_kernel_folder_fails_before_any_work(run_cli):
    code, err = run_cli("evaluate", "--seeds", "1", "--out", "/proc/stsf-gym-out")
    assert code == 2 and "/proc is not writable" in err and "Traceback" not in err


def test_a_baseline_that_is_no_python_with_stsf_gym_is_refused(run_cli, tmp_path):
    script = tmp_path / "not-python"
    script.write_text("#!/bin/sh\nexit 3\n")
    script.chmod(0o755)
    code, err = run_cli(
        "bench", "--step-only", "--baseline", str(script), "--out", str(tmp_path / "o")
    )
    assert code == 2 and "not a Python interpreter with stsf-gym installed" in err
    half = tmp_path / "half-checkout"
    (half / "stsf_gym").mkdir(parents=True)
    (half / "stsf_gym" / "__init__.py").write_text("")
    code, err = run_cli(
        "bench", "--step-only", "--baseline", str(half), "--out", str(tmp_path / "o")
    )
    assert code == 2 and "it lacks envs, agents, configs" in err


def test_an_observation_scale_of_zero_fails_before_the_training_folder_is_made(run_cli, tmp_path):
    code, err = run_cli("train", "--set", "observation.scale=0", "--out", str(tmp_path / "o"))
    assert code == 2 and "observation.scale must be > 0, got 0.0" in err
    assert not (tmp_path / "o").exists()


def test_a_finished_run_of_other_settings_is_kept_before_training_afresh(tmp_path, capsys):
    from stsf_gym.agents.training.replaced_runs import keep_replaced_run

    out = tmp_path / "run"
    before = finished_run(out)
    made_by = json.loads(before["train.json"])["made_by"]
    assert keep_replaced_run(out, made_by) is None and files(out) == before  # its own run
    kept = keep_replaced_run(out, {**made_by, "config": "another"})
    assert kept == out / "replaced-runs" / "0" and files(kept) == before
    assert not (out / "model.zip").exists() and "kept in" in capsys.readouterr().err
