"""Bad input on the command line exits 2 with one line naming it, before any work and with nothing
written: bad values and the config file that set them, output folders that cannot be written,
meaningless option combinations, a fault that could never act, a generator that can never make a
world."""

from __future__ import annotations

import os
import re

import pytest

from stsf_gym.validation import ConfigError


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["evaluate", "--estimators", "odometry,magic"], "unknown estimator 'magic'"),
        (["evaluate", "--agent", "path/that/does/not/exist.zip"], "path/that/does/not/exist.zip"),
        (["evaluate", "--set", "robot.wheel_radius=-1"], "robot.wheel_radius must be in (0, 10]"),
        (["evaluate", "--set", "world.start=[0,0,0]"], "use --world"),
        (["demo", "--set", "camera.width=0"], "camera.width must be in [1, 8192], got 0"),
        (["reproduce", "fig10", "--seeds", "0"], "--seeds must be at least 1"),
        (["train", "--seeds", "0"], "--seeds must be at least 1"),
        (["train", "--timesteps", "100"], "would end at 2048; ask for 2048"),
        (["benchmark", "--suite", "sparse", "--seed", "-1"], "--seed must be at least 0, got -1"),
        (
            ["benchmark", "--suite", "sparse", "--estimators", "stsf,ekf,stsf"],
            "'stsf' is named twice",
        ),
        (["evaluate", "--agent", "follower,follower"], "'follower' is named twice"),
        (  # a number typed with an exponent is read, then judged against the episode
            ["accuracy-curve", "--dial", "latency_s=1e6"],
            "--dial latency_s=1e+06: no measurement that old arrives in an episode of 420 s",
        ),
        (["accuracy-curve", "--dial", "rate_hz=1e-3"], "one measurement every 1000 s is none"),
        (["train", "--suite", "sparse", "--world", "straight_10m"], "drop --world/--split"),
        (["train", "--suite", "sparse", "--world", "irl_corridor"], "drop --world/--split"),
        (["train", "--world", "generated", "--split", "dev"], "split must be one of"),
        (["train", "--backend", "ray"], "--backend and --address are for a campaign"),
        (["train", "--estimators", "truth", "--workers", "0"], "--workers must be at least 1"),
        (["benchmark", "--suite", "sparse", "--agents", "no/such/folder"], "no/such/folder"),
        (
            ["train", "--suite", "corridor", "--set", "env.task.start_lateral=5"],
            "task.start_lateral 5 m across the path",
        ),
    ],
)
def test_cli_bad_input_exits_2_with_one_line_and_writes_nothing(run_cli, tmp_path, argv, message):
    out = tmp_path / "out"
    code, err = run_cli(*argv, "--out", str(out))
    command = argv[0]
    assert code == 2
    assert err.startswith(f"stsf-gym {command}: error: ") and message in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_cli_names_the_config_file_of_a_bad_value(run_cli, tmp_path):
    config = tmp_path / "bad.yaml"
    config.write_text("sonar:\n  dropout_prob: 2\n")
    code, err = run_cli("demo", "--config", str(config), "--out", str(tmp_path / "out"))
    assert code == 2 and f"{config}: sonar.dropout_prob must be in [0, 1], got 2" in err
    config.write_text("sonar: [unclosed\n")
    code, err = run_cli("demo", "--config", str(config), "--out", str(tmp_path / "out"))
    assert code == 2 and f"{config}: malformed YAML at line 2" in err


def test_cli_unwritable_out_fails_before_any_work(run_cli, tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    code, err = run_cli("evaluate", "--out", str(blocker / "results"))
    assert code == 2 and f"{blocker} is not a folder" in err
    assert blocker.read_text() == "not a folder"


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write into read-only folders")
def test_cli_read_only_out_fails_before_any_work(run_cli, tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    code, err = run_cli("evaluate", "--out", str(locked / "results"))
    assert code == 2 and "is not writable" in err
    assert list(locked.iterdir()) == []


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (  # a lens whose image folds over: no ray for the image corners
            ["evaluate", "--set", "camera.lens.distortion=[-3,0,0,0,0]"],
            "camera.lens.distortion .* folds the image over",
        ),
        (  # a landmark estimator on an env without a camera would run as odometry
            ["evaluate", "--estimators", "stsf", "--set", "camera.enabled=false"],
            "pose source 'stsf' reads the camera, but camera.enabled is false",
        ),
        (  # two options setting one value: neither may win silently
            ["demo", "--seconds", "5", "--set", "sim.max_episode_seconds=9"],
            "--seconds and sim.max_episode_seconds .* both set the episode length",
        ),
        (  # a number where a number is meant, not a boolean
            ["evaluate", "--set", "encoders.slip_std=true"],
            "encoders.slip_std must be a number, got True",
        ),
    ],
)
def test_meaningless_combinations_are_refused_before_any_work(run_cli, tmp_path, argv, message):
    out = tmp_path / "out"
    code, err = run_cli(*argv, "--out", str(out))
    assert code == 2 and re.search(message, err), err
    assert "Traceback" not in err and not out.exists()


def test_a_fault_that_could_never_act_is_refused(tmp_path, run_cli):
    faults = tmp_path / "late.yaml"
    faults.write_text("faults:\n  - {kind: kidnap, start: 500.0, shift: [0.3, 0.1], turn_deg: 8}\n")
    code, err = run_cli("evaluate", "--faults", str(faults), "--out", str(tmp_path / "out"))
    assert code == 2 and "late.yaml" in err
    assert "faults[0].start must be before the episode ends" in err


def test_a_generator_that_can_never_make_a_world_names_why(tmp_path):
    from stsf_gym.envs.config import load_config
    from stsf_gym.envs.worlds.generator import generate_world
    from stsf_gym.envs.worlds.generator_config import load_generator_config

    long = tmp_path / "long.yaml"
    long.write_text("min_path_length: 100\n")
    with pytest.raises(ConfigError, match=r"long\.yaml: generator\.min_path_length can never"):
        load_generator_config(long)
    narrow = load_generator_config({"width": [0.3, 0.4]})
    with pytest.raises(ConfigError, match=r"generator\.width .* narrower than the robot needs"):
        generate_world(1, narrow, load_config())
