"""Results say what made them (with the code their run loaded, in its workers too), and cached
work is reused only when the code and the fully resolved configuration that made it are
unchanged (:mod:`stsf_gym.results.provenance`)."""

from __future__ import annotations

import json
import shutil
import sys

import pytest
import yaml
from helpers import ROOT
from worker_jobs import import_module

import stsf_gym.envs.config as env_config
import stsf_gym.results.behaviour as behaviour
import stsf_gym.results.code_identity as code_identity
import stsf_gym.results.freshness as freshness
import stsf_gym.results.provenance as provenance
from stsf_gym import __version__
from stsf_gym.agents.model_files import model_metadata
from stsf_gym.agents.training.train import latest_checkpoint, train
from stsf_gym.config_files import CONFIG_DIR
from stsf_gym.experiments.evaluate import evaluate
from stsf_gym.experiments.jobs.backends import make_runner
from stsf_gym.experiments.jobs.store import read_rows
from stsf_gym.results.fingerprint import config_digest
from stsf_gym.results.run_context import RunContext, run_context

FAST = {"camera": {"enabled": False}, "sim": {"max_episode_seconds": 3.0}}
TINY_PPO = {
    "n_steps": 64,
    "batch_size": 32,
    "eval_freq": 1000,
    "checkpoint_freq": 64,
    "n_eval_episodes": 1,
    "env.sim.max_episode_seconds": 2.0,
}


def test_a_results_file_names_code_packages_config_seeds_and_command(tmp_path):
    with run_context(RunContext.of(["stsf-gym", "evaluate", "--seeds", "2"])):
        evaluate(tmp_path, ["odometry"], seeds=2, seed=5, world="straight_10m", workers=1, env=FAST)
    made_by = json.loads((tmp_path / "results.json").read_text())["provenance"]
    code = made_by["stsf_gym"]
    assert code["version"] == __version__ and len(code["source_digest"]) == 16
    assert code["commit"] is None or len(code["commit"]) == 40  # a checkout: its commit
    assert {"gymnasium", "pybullet", "numpy", "torch"} <= set(made_by["packages"])
    assert made_by["seeds"] == [5, 6]
    assert made_by["command"] == "stsf-gym evaluate --seeds 2"
    (config,) = made_by["config"].values()
    defaults = yaml.safe_load((CONFIG_DIR / "default.yaml").read_text())
    # every value, not only the overrides: a default nobody set is there too
    assert config["env"]["encoders"]["slip_std"] == defaults["encoders"]["slip_std"]
    assert config["env"]["sim"]["max_episode_seconds"] == 3.0  # and the override
    assert config["estimator"]["name"] == "odometry" and config["estimator"]["settings"]
    assert config["agent"]["follower"]["speed"] > 0


def test_the_code_a_run_loaded_includes_what_only_its_workers_imported(monkeypatch):
    module, path = "stsf_gym.recording.qos", "stsf_gym/recording/qos.py"
    monkeypatch.delitem(sys.modules, module, raising=False)  # this process never imports it
    assert path not in provenance.provenance()["stsf_gym"]["loaded_code"]
    jobs = [{"module": module, "n": n} for n in range(2)]
    done = list(make_runner("local", workers=2)(import_module, jobs))
    assert sorted(finished.result for _, finished in done) == [0, 1]  # as the jobs returned
    assert all(path in finished.modules for _, finished in done)  # each job's own code
    assert module not in sys.modules
    code = provenance.provenance()["stsf_gym"]["loaded_code"]
    assert code[path] == code_identity.file_digest(ROOT / path)
    assert code["stsf_gym/results/provenance.py"]  # a module this process imported
    assert "configs/default.yaml" in code and "configs/faults/soak.yaml" in code  # every config
    assert list(code) == sorted(code)


def _episode_stamps(folder):
    rows = read_rows(folder / "episodes" / "episodes.sqlite")
    return {key: row.written_ns for key, row in rows.items()}


@pytest.mark.slow
def test_an_edited_default_or_an_edited_module_recomputes_saved_episodes(
    tmp_path, monkeypatch, capsys
):
    run = lambda: evaluate(  # noqa: E731
        tmp_path, ["odometry"], seeds=1, world="straight_10m", workers=1, env=FAST
    )
    first, _ = run()
    stamps = _episode_stamps(tmp_path)
    run()
    assert _episode_stamps(tmp_path) == stamps  # same code and settings: reused
    assert "recomputing" not in capsys.readouterr().err

    edited = tmp_path / "configs"  # the package's configs with one default edited
    shutil.copytree(CONFIG_DIR, edited)
    defaults = yaml.safe_load((edited / "default.yaml").read_text())
    defaults["encoders"]["slip_std"] *= 4
    (edited / "default.yaml").write_text(yaml.safe_dump(defaults))
    monkeypatch.setattr(env_config, "CONFIG_DIR", edited)
    second, _ = run()
    assert "made by other code or settings" in capsys.readouterr().err
    assert _episode_stamps(tmp_path) != stamps
    assert second["rows"][0]["final_error_m"] != first["rows"][0]["final_error_m"]

    monkeypatch.setattr(env_config, "CONFIG_DIR", CONFIG_DIR)
    run()
    stamps = _episode_stamps(tmp_path)
    monkeypatch.setattr(code_identity, "source_digest", lambda: "edited-bytes")
    monkeypatch.setitem(behaviour.VERSIONS, "estimation", behaviour.VERSIONS["estimation"] + 1)
    run()  # other bytes, a declared version: neither decides; the code computes the same
    assert _episode_stamps(tmp_path) == stamps
    capsys.readouterr()
    digest = freshness.code_digest
    edited = "odometry_estimator.py"
    monkeypatch.setattr(
        freshness, "code_digest", lambda file: "edited" if file.name == edited else digest(file)
    )
    third, _ = run()
    assert "made by other code or settings" in capsys.readouterr().err
    assert _episode_stamps(tmp_path) != stamps
    assert third["rows"][0]["final_error_m"] == first["rows"][0]["final_error_m"]


@pytest.mark.slow
def test_a_checkpoint_of_other_code_is_set_aside_not_resumed(tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    train("ppo", "truth", out, 64, n_envs=1, overrides=TINY_PPO, progress_bar=False)
    assert latest_checkpoint(out)[1] == 64
    saved = model_metadata(out / "model.zip")
    assert saved["provenance"]["config"]["hyperparams"]["n_steps"] == 64
    monkeypatch.setitem(behaviour.VERSIONS, "learner", behaviour.VERSIONS["learner"] + 1)
    summary = train("ppo", "truth", out, 128, n_envs=1, overrides=TINY_PPO, progress_bar=False)
    assert "training starts afresh" in capsys.readouterr().err
    assert summary["resumed_from"] == 0 and summary["timesteps"] == 128
    assert (out / "stale-checkpoints" / "0").is_dir()
    made_by = json.loads((out / "train.json").read_text())["made_by"]
    assert made_by["code"] == behaviour.versions_digest()


@pytest.mark.parametrize("config", [{"a": 1, "b": [1, 2]}, {"b": [1, 2], "a": 1}])
def test_a_config_digest_ignores_key_order_and_sees_values(config):
    assert config_digest(config) == config_digest({"a": 1, "b": [1, 2]})
    assert config_digest({**config, "a": 2}) != config_digest(config)
