"""Quiet by default: PyBullet's C banners are captured; terminal tables fit the console."""

import os
import subprocess
import sys

import pytest
from helpers import ROOT
from rich.console import Console

from stsf_gym.envs.quiet import VERBOSE_ENV, quiet_c_output
from stsf_gym.terminal_table import NAME_WIDTH, fit_table, print_markdown

BANNERS = ("pybullet build time", "argv[0]", "EGL", "GL_VENDOR", "ven = ", "Destroy")
SCRIPT = """
import gymnasium as gym
import stsf_gym
env = gym.make("stsf_gym/Straight10m-v0", render_mode="rgb_array")
env.reset(seed=0)
env.step(env.action_space.sample())
env.render()
env.close()
print("finished")
"""


def _run(script: str, verbose: bool) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop(VERBOSE_ENV, None)
    if verbose:
        env[VERBOSE_ENV] = "1"
    return subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True
    )


@pytest.mark.slow
def test_env_lifecycle_prints_no_banner_unless_verbose():
    quiet = _run(SCRIPT, verbose=False)
    assert quiet.stdout == "finished\n"
    assert not any(banner in quiet.stderr for banner in BANNERS), quiet.stderr
    loud = _run(SCRIPT, verbose=True)
    assert "pybullet build time" in loud.stderr


def test_captured_text_is_dropped_or_shown_when_the_block_fails(capfd, monkeypatch):
    monkeypatch.delenv(VERBOSE_ENV, raising=False)
    with quiet_c_output():
        os.write(1, b"banner on stdout\n")
        os.write(2, b"banner on stderr\n")
    with pytest.raises(RuntimeError), quiet_c_output():
        os.write(1, b"why it failed\n")
        raise RuntimeError("plugin")
    out, err = capfd.readouterr()
    assert out == "" and err == "why it failed\n"
    monkeypatch.setenv(VERBOSE_ENV, "1")
    with quiet_c_output():
        os.write(1, b"shown\n")
    assert capfd.readouterr().out == "shown\n"


def _rendered(renderable, width: int) -> list[str]:
    console = Console(width=width, record=True, file=open(os.devnull, "w"))
    console.print(renderable)
    return console.export_text().splitlines()


@pytest.mark.parametrize("width", [40, 80, 200])
def test_tables_fit_the_console_and_name_the_columns_left_out(width):
    header = ["estimator", "success rate", "final error (m)", "RMS heading error (deg)", "NEES"]
    rows = [["conventional", 1.0, "0.003 ± 0.001", 0.186, 0.802], ["ekf", 0.5, "0.1", 0.05, 1.5]]
    table = fit_table(header, rows, width, rest_in="results.md")
    lines = _rendered(table, width)
    assert all(len(line.rstrip()) <= width for line in lines)
    text = "\n".join(lines)
    assert "conventional" in text and "0.003 ± 0.001" in text  # cells are never broken
    words = " ".join(text.split())
    for name in header[len(table.columns) :]:
        assert name in words  # named in the caption
    assert (len(table.columns) == len(header)) == (width >= 80)
    assert "0.186" in text or len(table.columns) < 4


def test_a_long_name_wraps_and_keeps_the_numbers_beside_it():
    header = ["estimator", "success rate", "final error (m)", "RMS heading error (deg)", "NEES"]
    name = "my_package.estimators:AVeryLongEstimatorName"
    rows = [[name, 1.0, "0.003 ± 0.001", 0.186, 0.802], ["ekf", 0.5, "0.1", 0.05, 1.5]]
    table = fit_table(header, rows, 80)
    lines = _rendered(table, 80)
    assert len(table.columns) == len(header)  # as with a short name
    assert all(len(line.rstrip()) <= 80 for line in lines)
    assert "0.003 ± 0.001" in "\n".join(lines)
    body = next(i for i, line in enumerate(lines) if line.startswith("─")) + 1
    parts = [line[:NAME_WIDTH].strip() for line in lines[body : body + 4]]
    assert "".join(parts) == name
    assert parts[:2] == ["my_package.", "estimators:"]  # broken where the name breaks


def test_markdown_reports_keep_their_prose():
    text = "# Title [not markup]\n\n| a | b |\n|---|---|\n| 1.5 | x |\n\nafter\n"
    console = Console(width=80, record=True, file=open(os.devnull, "w"))
    print_markdown(text, console)
    out = console.export_text()
    assert "# Title [not markup]" in out and "after" in out and "1.5" in out
    assert "|" not in out and "---" not in out


@pytest.mark.slow
@pytest.mark.parametrize("verbose", [False, True])
def test_cli_is_quiet_unless_verbose(tmp_path, verbose):
    command = [sys.executable, "-m", "stsf_gym.cli", "evaluate", "--estimators", "odometry"]
    command += ["--seeds", "1", "--workers", "1", "--out", str(tmp_path)]
    command += ["--set", "sim.max_episode_seconds=0.5", "--set", "camera.renderer=egl"]
    command += ["--verbose"] if verbose else []
    env = {k: v for k, v in os.environ.items() if k != VERBOSE_ENV}
    result = subprocess.run(
        command, capture_output=True, text=True, env={**env, "PYTHONPATH": str(ROOT)}, check=True
    )
    assert ("pybullet build time" in result.stderr) == verbose, result.stderr
    assert ("EGL device choice" in result.stderr) == verbose
    assert "odometry" in result.stdout
