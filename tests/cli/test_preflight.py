"""One pre-flight for every command's output paths and option combinations: bad input is
refused with one line naming it, exit code 2, before any work, nothing written."""

from __future__ import annotations

import gymnasium as gym
import pytest

from stsf_gym.validation import ConfigError


def _refused(run_cli, argv: list[str], message: str) -> str:
    """Run ``argv``; assert the one-line refusal holding ``message``; return it."""
    code, err = run_cli(*argv)
    assert code == 2, err
    assert err.startswith(f"stsf-gym {argv[0]}: error: ") and message in err, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    return err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["evaluate", "--estimators", ""], "--estimators names nothing, got ''"),
        (["evaluate", "--estimators", " , "], "--estimators names nothing"),
        (["benchmark", "--suite", "sparse", "--estimators", ""], "--estimators names nothing"),
        (["benchmark", "--suite", "sparse", "--agents", ","], "--agents names nothing"),
        (["train", "--estimators", ""], "--estimators names nothing"),
        (["replay", "no.mcap", "--estimators", ""], "--estimators names nothing"),
        (
            ["benchmark", "--suite", "sparse", "--worlds", "10001"],
            "episode seeds 0..10000 run past the split's 10000 worlds",
        ),
        (
            ["benchmark", "--suite", "corridor", "--seed", "9999", "--worlds", "2"],
            "episode seeds 9999..10000 run past",
        ),
        (
            ["accuracy-curve", "--suite", "corridor", "--seed", "9999", "--seeds", "3"],
            "episode seeds 9999..10001 run past",
        ),
        (
            ["accuracy-curve", "--suite", "sparse", "--world", "straight_10m"],
            "--suite picks the worlds",
        ),
        (["accuracy-curve", "--levels", "1,nan"], "--levels must be a finite number"),
        (["accuracy-curve", "--levels", "-1"], "--levels must be >= 0, got -1.0"),
        (["demo", "--record-frames", "jpeg"], "without --record nothing is recorded"),
        (["evaluate", "--record-frames", "png"], "without --record nothing is recorded"),
    ],
)
def test_meaningless_options_are_refused_before_any_work(run_cli, tmp_path, argv, message):
    out = tmp_path / "out"
    _refused(run_cli, [*argv, "--out", str(out)], message)
    assert not out.exists()


def test_an_out_that_is_a_file_is_refused(run_cli, tmp_path):
    blocker = tmp_path / "results"
    blocker.write_text("mine")
    _refused(run_cli, ["evaluate", "--out", str(blocker)], f"{blocker} is not a folder")
    assert blocker.read_text() == "mine"


def test_world_out_on_a_folder_is_refused(run_cli, tmp_path):
    (tmp_path / "kept.txt").write_text("mine")
    _refused(run_cli, ["world", "--out", str(tmp_path)], f"--out {tmp_path} is a folder")
    assert [p.name for p in tmp_path.iterdir()] == ["kept.txt"]


@pytest.mark.parametrize("command", [["benchmark", "--suite", "corridor"], ["evaluate"]])
def test_a_recordings_path_that_is_a_file_is_refused(run_cli, tmp_path, command):
    out = tmp_path / "out"
    recordings = out / ("corridor" if command[0] == "benchmark" else "") / "recordings"
    recordings.parent.mkdir(parents=True)
    recordings.write_text("not a folder")
    argv = [*command, "--record", "mcap", "--worlds" if command[0] == "benchmark" else "--seeds"]
    _refused(run_cli, [*argv, "1", "--out", str(out)], f"--record {recordings}")
    assert recordings.read_text() == "not a folder"
    assert [p for p in out.rglob("*") if p.is_file()] == [recordings]  # no cell, no result


def _suite_sweep(tmp_path, suite_text: str):
    suite = tmp_path / "my_suite.yaml"
    suite.write_text(suite_text)
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(f"base: {{suite: {suite}, estimator: odometry}}\ngrid: {{seeds: 1}}\n")
    return suite, sweep


@pytest.mark.parametrize(
    ("suite_text", "message"),
    [
        ("", "missing or empty: ['generator', 'env']"),
        ("generator: {}\nenv: {camera: {mode: fast}}\n", "missing or empty: ['generator']"),
        (
            "generator: {segments: [2, 3]}\nenv: {task: {protocol: reach}}\n",
            "env.task.protocol must be 'declare'",
        ),
    ],
)
def test_a_sweep_on_an_empty_or_protocol_less_suite_is_refused(
    run_cli, tmp_path, suite_text, message
):
    suite, sweep = _suite_sweep(tmp_path, suite_text)
    out = tmp_path / "out"
    err = _refused(run_cli, ["sweep", str(sweep), "--out", str(out)], message)
    assert str(suite) in err and not out.exists()


@pytest.mark.parametrize(
    "env_id",
    ["stsf_gym/Suite-Sparse-v0", "stsf_gym/Suite-Sparse-STSF-v0", "stsf_gym/Generated-v0"],
)
def test_a_world_given_to_an_env_that_draws_its_worlds_is_blamed(env_id):
    with pytest.raises(ConfigError, match="world 'irl_corridor' given to an env that draws") as err:
        gym.make(env_id, world="irl_corridor")
    assert err.value.key == "world"
