"""The sixth list of bad inputs, each refused in one line before any file is written: numbers a
user types (``1e-4``), duplicate levels, config files that are folders, keys written twice,
alias bombs and huge files."""

from __future__ import annotations

import re

import numpy as np
import pytest

from stsf_gym.config import parse_overrides
from stsf_gym.validation import ConfigError
from stsf_gym.yaml_layers import MAX_CONFIG_BYTES, read_yaml

# --- numbers a user types -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "number"),
    [("1e-4", 1e-4), ("1e6", 1e6), ("2E3", 2e3), ("1.5e3", 1.5e3), ("-3e+2", -300.0)],
)
def test_a_number_with_an_exponent_is_a_number(text, number):
    assert parse_overrides([f"finetune.learning_rate={text}"]) == {"finetune.learning_rate": number}


def test_a_finetune_learning_rate_typed_with_an_exponent_is_taken():
    from stsf_gym.agents.training.hyperparams import load_hyperparams

    overrides = parse_overrides(["finetune.learning_rate=1e-4"])
    settings = load_hyperparams("dagger+ppo", None, overrides=overrides, suite=True)
    assert settings.finetune.learning_rate == 1e-4


def test_a_level_given_twice_is_named(run_cli, tmp_path):
    code, err = run_cli("accuracy-curve", "--levels", "1,1.0", "--out", str(tmp_path / "o"))
    assert code == 2 and err.strip().endswith("--levels gives the level 1 twice, got '1,1.0'")
    assert not (tmp_path / "o").exists()


# --- config files ---------------------------------------------------------------------------


def write(tmp_path, text: str):
    path = tmp_path / "config.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "said"),
    [
        (
            "sim:\n  max_episode_seconds: 10.0\ncamera: {mode: fast}\nsim:\n  control_dt: 0.1\n",
            "line 4, column 1: key 'sim' is written twice (first at line 1)",
        ),
        ("camera: {mode: fast, mode: gl}\n", "line 1, column 22: key 'mode' is written twice"),
        (
            "a: &a [1, 1, 1, 1, 1, 1, 1, 1]\nb: &b [*a, *a, *a, *a, *a, *a, *a, *a]\nc: [*b, *b]\n",
            "line 1, column 4: config files take no YAML anchors or aliases",
        ),
    ],
)
def test_yaml_a_config_may_not_hold_is_refused_naming_file_and_line(tmp_path, text, said):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match=f"^{re.escape(f'{path}: {said}')}"):
        read_yaml(path)


def test_a_config_file_over_the_size_bound_is_refused_unread(tmp_path):
    path = write(tmp_path, "x: [" + "1," * (MAX_CONFIG_BYTES // 2) + "1]\n")
    with pytest.raises(ConfigError, match=rf"config file {path} holds 1\.0 MB, more than"):
        read_yaml(path)


def test_a_folder_as_config_says_it_is_a_folder(run_cli, tmp_path):
    code, err = run_cli("evaluate", "--config", str(tmp_path), "--out", str(tmp_path / "o"))
    assert code == 2 and f"config file {tmp_path} is a folder" in err
    assert not (tmp_path / "o").exists()


def test_an_alias_in_a_set_value_is_refused():
    with pytest.raises(ConfigError, match="override 'sim=\\*x': config files take no YAML"):
        parse_overrides(["sim=*x"])


# --- agent names ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "said"),
    [
        (
            "json:JSONDecoder",
            "made a JSONDecoder, which is not an agent: it lacks wrap, begin, act",
        ),
        ("builtins:print", "made a NoneType, which is not an agent: it lacks wrap"),
        ("os:path", "agent 'os:path' is a module, not an agent class"),
        ("", "an agent name may not be empty, got ''"),
        (" ", "an agent name may not be empty, got ' '"),
    ],
)
def test_a_name_that_makes_no_agent_is_refused_naming_what_is_missing(name, said):
    from stsf_gym.agents.registry import make_agent

    with pytest.raises(ConfigError, match=re.escape(said)):
        make_agent(name)


def test_an_object_that_is_not_an_agent_is_refused_on_the_command_line(run_cli, tmp_path):
    code, err = run_cli("evaluate", "--agent", "json:JSONDecoder", "--out", str(tmp_path / "o"))
    assert code == 2 and len(err.strip().splitlines()) == 1 and "not an agent" in err
    assert not (tmp_path / "o").exists()


def test_a_symlink_loop_as_a_model_is_refused(tmp_path):
    from stsf_gym.agents.registry import make_agent

    (tmp_path / "a.zip").symlink_to(tmp_path / "b.zip")
    (tmp_path / "b.zip").symlink_to(tmp_path / "a.zip")
    with pytest.raises(ConfigError, match=r"a\.zip cannot be followed"):
        make_agent(str(tmp_path / "a.zip"))


def test_an_alias_and_its_shipped_name_are_one_agent_named_twice():
    from stsf_gym.experiments.benchmark.trained import expand_agents

    alias, canonical = "pretrained:corridor/ppo-truth", "pretrained:corridor/dagger-truth"
    with pytest.raises(ConfigError, match=f"{alias!r} and {canonical!r} name the same agent"):
        expand_agents(["follower", alias, canonical])
    assert expand_agents(["follower", canonical]) == ["follower", *expand_agents([alias])]


# --- the env and its wrappers ---------------------------------------------------------------

FAST = {"camera": {"mode": "fast"}}


def test_camera_pointing_with_no_estimate_under_it_says_what_it_needs(make_env):
    from stsf_gym.wrappers.pointing import CameraPointingWrapper

    env = make_env("stsf_gym/Corridor-v0", camera={"mode": "fast", "control": "pan"})
    with pytest.raises(ValueError, match="it needs a PoseEstimateWrapper under it"):
        CameraPointingWrapper(env)


def test_an_estimate_over_an_estimate_is_refused(make_env):
    from stsf_gym.wrappers import PoseEstimateWrapper

    env = make_env("stsf_gym/Corridor-Truth-v0", **FAST)
    with pytest.raises(ValueError, match="has 'pose' already \\(pose source 'truth'\\)"):
        PoseEstimateWrapper(env, "odometry")


@pytest.mark.parametrize("env_id", ["stsf_gym/Corridor-v0", "stsf_gym/Suite-Corridor-Truth-v0"])
@pytest.mark.parametrize("call", ["step", "reset"])
def test_a_call_after_close_says_the_env_is_closed(make_env, env_id, call):
    env = make_env(env_id, **FAST)
    env.reset(seed=0)
    env.close()
    with pytest.raises(RuntimeError, match=f"^{call}\\(\\) after close\\(\\): this env is closed"):
        env.step(env.action_space.sample()) if call == "step" else env.reset(seed=0)


def test_a_refused_first_reset_leaves_the_env_stepping_after_a_valid_one(make_env):
    env = make_env("stsf_gym/Corridor-v0", **FAST)
    with pytest.raises(ValueError, match="start_pose must be inside the walls' bounds"):
        env.reset(seed=0, options={"start_pose": [1e5, 0.0, 0.0]})
    env.reset(seed=0)
    *_, info = env.step(env.action_space.sample())
    assert info["sim_time"] > 0


@pytest.mark.parametrize(
    ("start", "said"),
    [
        ([7.0, 5.0, 0.0], "is outside the corridor: walls part it from the path's start"),
        ([0.0, 0.0, 1e12], "yaw must be an angle in radians within ±12.57 (two turns), got 1e+12"),
        ([0.0, 0.0, float("inf")], "must be three finite numbers"),
    ],
)
def test_a_start_pose_off_the_corridor_or_with_an_absurd_yaw_is_refused(make_env, start, said):
    env = make_env("stsf_gym/Corridor-v0", **FAST)  # the IRL corridor: an L round [7, 5]
    with pytest.raises(ValueError, match=re.escape(said)):
        env.reset(seed=0, options={"start_pose": start})
    _, info = env.reset(seed=0, options={"start_pose": [7.0, 0.0, 2 * np.pi]})  # in the corridor
    assert info["true_pose"][:2] == pytest.approx([7.0, 0.0], abs=0.01)


def test_an_action_of_a_batch_shape_is_refused_with_the_expected_shape(make_env):
    env = make_env("stsf_gym/Corridor-v0", **FAST)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=re.escape("action must have shape (2,), got (1, 2)")):
        env.step(np.zeros((1, 2), np.float32))


# --- fifth list, one left ---------------------------------------------------------------------


def test_a_baseline_that_exits_0_saying_nothing_is_refused(run_cli, tmp_path):
    true = tmp_path / "true"  # as /bin/true: any arguments, exit 0, no output
    true.write_text("#!/bin/sh\nexit 0\n")
    true.chmod(0o755)
    code, err = run_cli(
        "bench", "--step-only", "--baseline", str(true), "--out", str(tmp_path / "o")
    )
    assert code == 2 and err.strip().endswith("exited 0 and printed nothing)")
    assert not (tmp_path / "o").exists()


# --- cached results edited by hand, strict JSON ---------------------------------------------

RADIUS = {"env": {"task": {"goal_radius": 0.25}}}


def stop(distance: float, success: bool) -> dict:
    return {"goal": 0, "time": 1.0, "position": [0.0, 0.0], "true_distance_m": distance,
            "success": success}  # fmt: skip


@pytest.mark.parametrize(
    ("result", "said"),
    [
        ([1, 2], "its result is a list, not a mapping"),
        ({"finite": True, "estimates": [[0.0, float("nan"), 0.0]]}, "estimates[0][1] holds nan"),
        ({"finite": True, "stops": [stop(5.0, True)]}, "stops[0] is marked a success 5 m from"),
        ({"finite": True, "stops": [stop(0.1, False)]}, "stops[0] is marked a miss 0.1 m from"),
    ],
)
def test_an_episode_edited_by_hand_fails_its_own_check(result, said):
    from stsf_gym.experiments.jobs.checks import episode_problem

    assert said in episode_problem(result, RADIUS)


def test_an_episode_as_the_code_writes_it_passes_its_check():
    from stsf_gym.experiments.jobs.checks import cell_problem, episode_problem

    diverged = {"finite": False, "estimates": [[float("nan")] * 3], "stops": [stop(0.1, True)]}
    assert episode_problem(diverged, RADIUS) is None
    cell = {"outcome": "goal", "metrics": {"nis_mean": None}, "navigation": {"stops": []}}
    assert cell_problem(cell, RADIUS) is None
    assert "result['metrics']['ate_rmse_m'] holds nan" in cell_problem(
        {**cell, "metrics": {"ate_rmse_m": float("nan")}}, RADIUS
    )


def test_a_saved_result_that_fails_its_check_is_recomputed_and_named(tmp_path, capsys):
    import sqlite3

    from stsf_gym.experiments.jobs.cache import run_cached
    from stsf_gym.experiments.jobs.checks import cell_problem
    from stsf_gym.experiments.jobs.spec import Finished

    def runner(fn, jobs):
        return ((job, Finished(fn(job), ["stsf_gym/metrics.py"])) for job in jobs)

    def run(job: dict) -> dict:
        return {"outcome": "goal", "navigation": {"stops": [stop(0.1, True)]}}

    def stored() -> str:
        with sqlite3.connect(store) as db:
            return db.execute("SELECT result FROM results WHERE key = 'cell'").fetchone()[0]

    store = tmp_path / "cells.sqlite"
    jobs = [{"seed": 0}]
    args = (jobs, store, lambda job: "cell", runner, "cells", lambda job: RADIUS)
    run_cached(run, *args, check=cell_problem)
    edited = stored().replace("0.1", "5.0")  # a stop 5 m off, marked a success, by hand
    with sqlite3.connect(store) as db:
        db.execute("UPDATE results SET result = ? WHERE key = 'cell'", (edited,))
    assert run_cached(run, *args, check=cell_problem) == [run({})]
    err = capsys.readouterr().err
    assert "1 saved result(s) in" in err and "fail their own check" in err
    assert "(e.g. cell: stops[0] is marked a success 5 m from its goal" in err
    assert '"true_distance_m": 0.1' in stored()  # recomputed


def test_json_files_hold_no_nan(tmp_path):
    import json

    from stsf_gym.io import write_json

    path = write_json(tmp_path / "results.json", {"ate": float("nan"), "v": np.array([np.inf, 1])})
    assert "NaN" not in path.read_text() and "Infinity" not in path.read_text()
    assert json.loads(path.read_text()) == {"ate": None, "v": [None, 1.0]}


def test_a_full_disk_is_one_line_saying_what_was_saved_stays_valid(run_cli, tmp_path, monkeypatch):
    import errno
    import os

    def full(src, dst):
        raise OSError(errno.ENOSPC, "No space left on device", str(dst))

    monkeypatch.setattr(os, "replace", full)
    out = tmp_path / "world.yaml"
    code, err = run_cli("world", "--seed", "1", "--out", str(out))
    assert code == 1 and len(err.strip().splitlines()) == 1
    assert f"the disk is full writing {out}; every file saved before stays valid" in err
    assert list(tmp_path.iterdir()) == []  # the temporary file is gone too


# --- a run that cannot be resumed -----------------------------------------------------------


def test_an_episodes_file_with_its_header_only_reads_as_no_rows(tmp_path):
    from stsf_gym.agents.training.training_log import plot_learning_curve, read_rows

    (tmp_path / "episodes.csv").write_text("timesteps,reward,length,success,control_steps\n")
    assert read_rows(tmp_path / "episodes.csv").shape == (0, 5)
    assert plot_learning_curve(tmp_path, "dagger+ppo on truth").is_file()  # set aside: plotted


def test_a_fine_tuning_setting_changed_keeps_the_demonstrations():
    from stsf_gym.agents.training.settings import resolve_run

    def meta(*overrides: str) -> dict:
        run = resolve_run(
            "dagger+ppo", "truth", 16384, 0, "generated", None, parse_overrides(list(overrides)),
            1, "corridor",
        )  # fmt: skip
        return run.meta

    base, tuned = meta(), meta("finetune.learning_rate=1e-5")
    assert tuned["made_by"] != base["made_by"]  # the reward stage is trained again
    assert tuned["demonstrations_made_by"] == base["demonstrations_made_by"]
    rounds = meta("demonstrations.rounds=1")
    assert rounds["demonstrations_made_by"] != base["demonstrations_made_by"]


# --- Ray ------------------------------------------------------------------------------------


def test_an_address_where_a_service_that_is_not_ray_answers_is_refused():
    import socket
    import threading

    from stsf_gym.experiments.jobs.backends import check_ray_address

    server = socket.create_server(("127.0.0.1", 0))
    threading.Thread(target=lambda: [server.accept() for _ in range(8)], daemon=True).start()
    address = f"127.0.0.1:{server.getsockname()[1]}"
    with pytest.raises(ConfigError, match=f"^--address {address}: no Ray cluster"):
        check_ray_address(address, join_timeout_s=3.0)  # joined, late or refused: one line
    server.close()


@pytest.mark.slow
def test_address_auto_without_a_cluster_is_one_line(run_cli, tmp_path):
    pytest.importorskip("ray")
    out = tmp_path / "o"
    argv = ["--suite", "corridor", "--worlds", "1", "--agents", "follower", "--out", str(out)]
    code, err = run_cli("benchmark", *argv, "--backend", "ray", "--address", "auto")
    assert code == 2 and "--address auto: no Ray cluster to join (ConnectionError" in err
    assert not out.exists()


def _alive(pid: int) -> bool:
    from stsf_gym.experiments.jobs.orphan_watchdog import _processes

    return pid in _processes()


def test_the_watchdog_kills_what_a_killed_run_left(tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    code = (
        "import subprocess, sys, time\n"
        "from stsf_gym.experiments.jobs.orphan_watchdog import start_watchdog\n"
        "child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(600)'])\n"
        "start_watchdog(); print(child.pid, flush=True); time.sleep(600)\n"
    )
    run = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    child = int(run.stdout.readline())
    time.sleep(2.5)  # the watchdog notes the child (every POLL_S)
    os.kill(run.pid, signal.SIGKILL)
    run.wait()
    for _ in range(100):  # the watchdog sees the run gone within a POLL_S
        if not _alive(child):
            break
        time.sleep(0.2)
    assert not _alive(child)


@pytest.mark.slow
def test_a_driver_killed_with_sigkill_leaves_no_ray_process():
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    pytest.importorskip("ray")
    from stsf_gym.experiments.jobs.orphan_watchdog import descendants

    script = Path(__file__).with_name("ray_kill_driver.py")
    driver = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    assert int(driver.stdout.readline()) == driver.pid
    left = set(descendants(driver.pid))
    os.kill(driver.pid, signal.SIGKILL)
    driver.wait()
    for _ in range(150):
        if not any(_alive(pid) for pid in left):
            break
        time.sleep(0.2)
    assert not [pid for pid in left if _alive(pid)]
