"""Each run keeps its own provenance (:mod:`stsf_gym.results.run_context`): the command the
CLI was given, and the worker modules and data files it noted, seen by no other run in the
process."""

from __future__ import annotations

import json
import sys

from helpers import ROOT
from worker_jobs import import_module

from stsf_gym.agents import pretrained
from stsf_gym.experiments.jobs.backends import make_runner
from stsf_gym.results.code_identity import file_digest, loaded_code
from stsf_gym.results.command import command_line
from stsf_gym.results.run_context import RunContext, current_run, run_context

QOS_MODULE, QOS_PATH = "stsf_gym.recording.qos", "stsf_gym/recording/qos.py"
AGENT = "pretrained:corridor/dagger-truth"


def test_two_runs_in_one_process_do_not_see_each_others_workers_or_data_files(monkeypatch, own_run):
    monkeypatch.delitem(sys.modules, QOS_MODULE, raising=False)  # only a worker imports it
    with run_context() as first:
        models = pretrained.models(AGENT)
        done = list(
            make_runner("local", workers=2)(import_module, [{"module": QOS_MODULE, "n": 0}])
        )
        assert [finished.result for _, finished in done] == [0]
        code = loaded_code()
    data = {f"agents/pretrained/trained-models/corridor/dagger-truth/{m.name}" for m in models}
    assert QOS_PATH in code and data <= set(code)
    assert code[QOS_PATH] == file_digest(ROOT / QOS_PATH)
    with run_context() as second:
        assert QOS_PATH not in loaded_code() and not data & set(loaded_code())
    assert not second.worker_modules and not second.data_files
    assert QOS_PATH in first.worker_modules and data == first.data_files
    assert not own_run.worker_modules and not own_run.data_files  # the test's run: nothing leaked


def test_a_runner_notes_its_workers_into_the_run_it_was_made_for():
    """The job engine carries its run: jobs consumed under another context still count as
    the run that started them."""
    with run_context() as made_for:
        runner = make_runner("local", workers=2)
    with run_context() as other:
        list(runner(import_module, [{"module": "json", "n": 0}]))
    assert made_for.worker_modules and not other.worker_modules


def test_a_block_restores_the_run_before_it():
    before = current_run()
    with run_context(RunContext.of(["stsf-gym", "demo"])) as run:
        assert current_run() is run and command_line() == "stsf-gym demo"
    assert current_run() is before
    assert RunContext().argv() == sys.argv  # a run not started by the CLI: this process's


def test_the_command_recorded_is_the_one_the_cli_was_given(run_cli, tmp_path):
    out = tmp_path / "o"
    argv = ["evaluate", "--estimators", "odometry", "--world", "straight_10m", "--seeds", "1"]
    argv += [
        "--workers",
        "1",
        "--set",
        "camera.enabled=false",
        "--set",
        "sim.max_episode_seconds=3",
        "--out",
        str(out),
    ]
    code, err = run_cli(*argv)
    assert code == 0, err
    made_by = json.loads((out / "results.json").read_text())["provenance"]
    assert made_by["command"] == " ".join(["stsf-gym", *argv[:-1], "OUT"])
    assert command_line() != made_by["command"]  # the CLI's run ended with its command
