import json
import subprocess
import sys

import pytest

from stsf_gym.results import check_rows

CLI = [sys.executable, "-m", "stsf_gym.cli"]


@pytest.mark.slow
def test_demo_json_and_files(tmp_path):
    out = tmp_path / "demo"
    demo = ["demo", "--worlds", "1", "--seconds", "3", "--seed", "1", "--out", str(out), "--json"]
    result = subprocess.run(
        [*CLI, *demo],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)  # stdout holds nothing but the JSON
    assert summary["seeds"] == [1, 1] and summary["suite"] == "sparse"
    assert [row["estimator"] for row in summary["rows"]] == ["odometry", "stsf", "ekf", "mcl"]
    check_rows(summary["rows"])
    assert all(row["success_rate"]["mean"] == 0.0 for row in summary["rows"])  # 3 s: too short
    assert (out / "trajectories.png").stat().st_size > 10_000
    assert json.loads((out / "results.json").read_text())["rows"][0]["episodes"] == 1
    assert "too few to separate anything" in (out / "results.md").read_text()
    assert (out / summary["video"]).stat().st_size > 5_000  # one video, of the episodes run
    assert "demo: episodes: 4 episode(s) to run" in result.stderr  # said before the work


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "message"),
    [(["--set", "camera.widht=3"], "camera.widht"), (["--seconds", "-1"], "--seconds")],
)
def test_bad_arguments_named(tmp_path, args, message):
    result = subprocess.run(
        [*CLI, "demo", "--out", str(tmp_path), *args], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 2
    assert message in result.stderr


def test_help_lists_commands():
    result = subprocess.run([*CLI, "--help"], capture_output=True, text=True)
    assert result.returncode == 0 and "demo" in result.stdout


@pytest.mark.slow
def test_only_validation_errors_are_bad_input(tmp_path):
    """A bad log is the user's (exit 2, one line naming the file); a ValueError from deep in a
    run is a bug: its traceback is kept and the exit code is not 2."""
    log = tmp_path / "not-a-log.mcap"
    log.write_text("no MCAP here")
    replay = ["replay", str(log), "--estimators", "odometry", "--out", str(tmp_path / "r")]
    bad = subprocess.run([*CLI, *replay], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    assert f"{log}: not a readable MCAP log" in bad.stderr
    bug = (
        "import sys, stsf_gym.experiments.replay as r, stsf_gym.cli as c\n"
        "def broken(*args): raise ValueError('operands could not be broadcast together')\n"
        "r.replay_logs = broken\n"
        "sys.exit(c.main(sys.argv[1:]))\n"
    )
    crash = subprocess.run(
        [sys.executable, "-c", bug, *replay], capture_output=True, text=True, timeout=120
    )
    assert crash.returncode not in (0, 2), crash.stderr
    assert "Traceback" in crash.stderr and "could not be broadcast" in crash.stderr


@pytest.mark.slow
def test_train_without_an_evaluation_says_so(tmp_path):
    """A run shorter than eval_freq evaluates nothing: said in words, not 'success rate nan'."""
    train = ["train", "--algo", "ppo", "--estimator", "truth", "--timesteps", "64"]
    train += ["--n-envs", "1", "--set", "n_steps=64", "--set", "batch_size=32"]
    train += ["--set", "env.sim.max_episode_seconds=3", "--out", str(tmp_path)]
    result = subprocess.run([*CLI, *train], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "no evaluation ran (fewer timesteps than eval_freq)" in result.stdout
    assert "nan" not in result.stdout


@pytest.mark.parametrize("command", ["evaluate", "demo"])
def test_every_episode_command_takes_the_ray_backend(command, monkeypatch, tmp_path):
    """``--backend``/``--address`` reach the API of the commands that run episodes."""
    import importlib

    from stsf_gym import cli

    handler = importlib.import_module(f"stsf_gym.cli.{command}")
    api = {"evaluate": "evaluate_agents", "demo": "run_demo"}[command]
    seen = {}

    def record(*args):
        seen["backend"], seen["address"] = args[-2:]
        raise SystemExit(0)

    monkeypatch.setattr(handler, api, record)
    argv = [command, "--backend", "ray", "--address", "auto", "--out", str(tmp_path / "o")]
    with pytest.raises(SystemExit):
        cli.main(argv)
    assert seen == {"backend": "ray", "address": "auto"}
