"""Sweeps: grid expansion and key checks, a local run (CLI) that resumes, failed cells that are
reported and retried, and the same sweep on Ray giving the same table."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import pytest
import yaml

from stsf_gym.estimators import estimator_settings
from stsf_gym.experiments.jobs import cells as sweep_cells
from stsf_gym.experiments.jobs.cells import CellKind
from stsf_gym.experiments.jobs.store import read_rows
from stsf_gym.experiments.sweep.run import run_sweep
from stsf_gym.experiments.sweep.spec import load_sweep
from stsf_gym.results import check_rows
from stsf_gym.validation import ConfigError

TINY = {  # 2 estimators x 1 noise key x 2 levels x 1 seed, 12 s episodes, fast camera
    "base": {
        "world": "straight_10m",
        "env": {"camera": {"mode": "fast"}, "sim": {"max_episode_seconds": 12.0}},
    },
    "grid": {
        "estimator": ["odometry", "stsf"],
        "env.encoders.radius_error_std": [0.0033, 0.0264],
        "seeds": 1,
    },
}


def write_sweep(folder, doc: dict, name: str = "tiny"):
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


@pytest.fixture(scope="module")
def local_run(tmp_path_factory):
    """The tiny sweep through the CLI, in two local processes."""
    folder = tmp_path_factory.mktemp("local")
    path = write_sweep(folder, TINY)
    command = [sys.executable, "-m", "stsf_gym.cli", "sweep", str(path), "--out", str(folder)]
    done = subprocess.run([*command, "--json"], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return path, folder / "tiny", json.loads(done.stdout)


def test_grid_and_one_at_a_time_cells(tmp_path):
    doc = {
        "base": {"world": "straight_10m", "seed": 5, "env": {"sim": {"max_episode_seconds": 9}}},
        "grid": {"estimator": ["odometry", "ekf"], "seeds": 2},
        "one_at_a_time": {
            "env.encoders.slip_std": [0.001, 0.01],
            "env.camera.sensor.read_noise": [1.0, 4.0, 8.0],
        },
    }
    cells = load_sweep(write_sweep(tmp_path, doc), seed=100).cells
    assert len(cells) == 2 * 2 * (2 + 3)
    assert sorted({c["seed"] for c in cells}) == [105, 106]  # base seed on, shifted by --seed
    slip = [c for c in cells if "env.encoders.slip_std" in c["values"]]
    assert len(slip) == 8 and all("camera" not in c["env"] for c in slip)
    assert all(c["env"]["sim"]["max_episode_seconds"] == 9 for c in cells)  # base env kept
    noise = {c["env"]["camera"]["sensor"]["read_noise"] for c in cells if c not in slip}
    assert noise == {1.0, 4.0, 8.0}
    assert cells[0]["options"] == dataclasses.asdict(estimator_settings("odometry"))
    assert cells[-1]["options"]["sigma_px"] > 0  # ekf.yaml


def test_fault_sets_by_name(tmp_path):
    doc = {"base": {"estimator": "ekf"}, "grid": {"faults": ["none", "kidnap"]}}
    clean, kidnapped = load_sweep(write_sweep(tmp_path, doc)).cells
    assert "faults" not in clean["env"]
    assert [f["kind"] for f in kidnapped["env"]["faults"]] == ["kidnap"]
    assert kidnapped["values"] == {"faults": "kidnap"}


@pytest.mark.parametrize(
    ("doc", "named"),
    [
        ({"grid": {"estimator": ["stsf"], "sede": [1]}}, "grid.sede"),
        ({"grid": {"estimator": ["stsf"], "env.camera.fsat": [1]}}, "camera.fsat"),
        ({"grid": {"estimator": ["stsf"], "env.sonar.count": ["x"]}}, "sonar.count"),
        ({"grid": {"estimator": ["stsf", "gps"]}}, "'gps'"),
        ({"base": {"estimator": "stsf", "wrold": "x"}}, "'base.wrold'"),
        ({"base": {"estimator": "stsf", "kind": "nope"}}, "base.kind"),
        ({"base": {"estimator": "stsf"}, "grid": {"seeds": 0}}, "grid.seeds"),
        ({"base": {"estimator": "stsf"}, "grdi": {}}, "'grdi'"),
        ({"grid": {"seeds": 2}}, "no estimator"),
        ({"grid": {"estimator": ["stsf"], "train.algo": ["sac"]}}, "'grid.train.algo'"),
        ({"grid": {"estimator": ["stsf", "ekf", "stsf"]}}, "grid.estimator repeats"),
        ({"grid": {"estimator": ["ekf"], "faults": ["none", "kidnapp"]}}, "'kidnapp'"),
        ({"grid": {"estimator": ["ekf"]}, "one_at_a_time": {"estimator": ["stsf"]}}, "both"),
    ],
)
def test_bad_sweeps_name_file_and_key(tmp_path, doc, named):
    path = write_sweep(tmp_path, doc, "bad")
    with pytest.raises(ConfigError, match=r"bad\.yaml") as error:
        load_sweep(path)
    assert named in str(error.value)


def test_train_cells_carry_trainer_options_and_check_them(tmp_path):
    doc = {
        "base": {"kind": "train", "world": "straight_10m", "train": {"timesteps": 64}},
        "grid": {"estimator": ["truth", "stsf"], "train.learning_rate": [1e-3, 1e-4]},
    }
    cells = load_sweep(write_sweep(tmp_path, doc)).cells
    assert [c["train"] for c in cells[:2]] == [
        {"timesteps": 64, "learning_rate": 1e-3},
        {"timesteps": 64, "learning_rate": 1e-4},
    ]
    doc["grid"]["train.learning_rte"] = [1e-3]
    with pytest.raises(ConfigError, match="learning_rte"):
        load_sweep(write_sweep(tmp_path, doc))


@pytest.mark.slow
def test_local_sweep_writes_summary_and_resumes(local_run, monkeypatch):
    path, out, summary = local_run
    assert summary["cells"] == summary["finished"] == 4 and summary["failed"] == []
    assert len(read_rows(out / "cells.sqlite")) == 4
    assert (out / "errors.png").stat().st_size > 0
    groups = {
        (g["values"]["estimator"], g["values"]["env.encoders.radius_error_std"]): g["metrics"]
        for g in summary["groups"]
    }
    assert len(groups) == 4 and all(m["final_error_m"]["count"] == 1 for m in groups.values())
    check_rows([g["metrics"] for g in summary["groups"]], "groups")
    odometry = [groups["odometry", level]["final_error_m"]["mean"] for level in (0.0033, 0.0264)]
    assert odometry[0] != odometry[1]  # the swept noise reached the env
    table = (out / "results.md").read_text()
    stamps = {k: row.written_ns for k, row in read_rows(out / "cells.sqlite").items()}
    calls = []
    monkeypatch.setitem(sweep_cells.CELL_KINDS, "evaluate", CellKind(calls.append))
    again = run_sweep(path, out, workers=1)
    assert calls == [] and again["groups"] == summary["groups"]
    assert (out / "results.md").read_text() == table
    assert {k: row.written_ns for k, row in read_rows(out / "cells.sqlite").items()} == stamps


def fake_cell(cell: dict) -> dict:
    """Metrics from the cell itself; the STSF cells fail."""
    if cell["estimator"] == "stsf":
        raise RuntimeError(f"no landmarks for seed {cell['seed']}")
    level = cell["values"]["env.encoders.slip_std"]
    return {"metrics": {"final_error_m": level * (1 + cell["seed"]), "ate_rmse_m": level}}


@pytest.mark.slow
def test_failed_cells_are_reported_and_retried(tmp_path, monkeypatch):
    doc = {
        "base": {"world": "straight_10m"},
        "grid": {"estimator": ["odometry", "stsf"], "seeds": 2},
        "one_at_a_time": {"env.encoders.slip_std": [0.01, 0.02]},
    }
    path = write_sweep(tmp_path, doc)
    calls = []

    def counted(cell):
        calls.append(cell["estimator"])
        return fake_cell(cell)

    monkeypatch.setitem(sweep_cells.CELL_KINDS, "evaluate", CellKind(counted))
    summary = run_sweep(path, tmp_path / "out", workers=1)
    assert summary["finished"] == 4 and len(summary["failed"]) == 4
    assert summary["failed"][0]["error"] == "RuntimeError: no landmarks for seed 0"
    odometry = summary["groups"][0]
    assert odometry["values"] == {"estimator": "odometry", "env.encoders.slip_std": 0.01}
    assert odometry["metrics"]["final_error_m"]["mean"] == pytest.approx(0.015)
    assert odometry["metrics"]["final_error_m"]["values"] == pytest.approx([0.01, 0.02])
    assert "## Failed cells" in (tmp_path / "out" / "results.md").read_text()
    calls.clear()
    monkeypatch.setitem(
        sweep_cells.CELL_KINDS, "evaluate", CellKind(lambda c: counted({**c, "estimator": "ok"}))
    )
    again = run_sweep(path, tmp_path / "out", workers=1)
    assert calls == ["ok"] * 4  # only the failed cells ran again
    assert again["finished"] == 8 and again["failed"] == []


@pytest.mark.slow
def test_ray_gives_the_local_table(local_run, tmp_path):
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'stsf-gym[ray]')")
    path, out, summary = local_run
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        on_ray = run_sweep(path, tmp_path, backend="ray")
    finally:
        ray.shutdown()
    assert on_ray["groups"] == summary["groups"]
    assert (tmp_path / "results.md").read_text() == (out / "results.md").read_text()
    assert sorted(read_rows(tmp_path / "cells.sqlite")) == sorted(read_rows(out / "cells.sqlite"))


def test_a_sweep_on_a_suite_runs_its_test_worlds_and_task():
    from stsf_gym.config_files import CONFIG_DIR

    sweep = load_sweep(CONFIG_DIR / "sweeps" / "sonar_beam.yaml")
    assert len(sweep.cells) == 2 * 2 * 20
    cell = sweep.cells[0]
    assert cell["world"] == "generated:test"
    assert cell["env"]["task"]["protocol"] == "declare"  # the suite's task ...
    assert cell["env"]["generator"]["halls"] == [1, 1]  # ... and its worlds
    assert {c["env"]["sonar"]["beam"]["enabled"] for c in sweep.cells} == {False, True}


def test_an_unknown_suite_in_a_sweep_is_named(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("base: {suite: attic}\ngrid: {estimator: [odometry]}\n")
    with pytest.raises(ConfigError, match=r"bad.yaml: base.suite: unknown suite 'attic'"):
        load_sweep(path)


def test_paired_differences_of_a_two_valued_key():
    from stsf_gym.experiments.sweep.paired import paired_differences

    cells, results = [], []
    for estimator in ("odometry", "stsf"):
        for beam in (False, True):
            for seed in range(6):
                values = {"estimator": estimator, "env.sonar.beam.enabled": beam, "seed": seed}
                cells.append({"seed": seed, "values": values})
                lost = estimator == "odometry" and beam and seed < 4  # the beam model hurts
                results.append({"outcome": "collision" if lost else "goal"})
    results[0] = {"error": "RuntimeError: crashed"}  # odometry, beam off, seed 0: unpaired
    paired = paired_differences(cells, results)
    beam = {p["others"]["estimator"]: p for p in paired if p["key"] == "env.sonar.beam.enabled"}
    assert set(beam) == {"odometry", "stsf"}
    odometry = beam["odometry"]
    assert odometry["values"] == [False, True]
    assert odometry["pairs"] == 5 and odometry["difference"] == pytest.approx(-3 / 5)
    assert odometry["high"] < 0 and odometry["only_second"] == 3
    assert beam["stsf"]["difference"] == 0.0
    on = [p for p in paired if p["key"] == "estimator" and p["others"]["env.sonar.beam.enabled"]]
    assert on[0]["difference"] == pytest.approx(4 / 6)  # stsf - odometry with the beam model
