"""examples/: every script runs as documented, and every one is run by a test."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest
from helpers import ROOT
from PIL import Image

EXAMPLES = ROOT / "examples"


def run(script: str, *args: str) -> str:
    """Run ``examples/<script>`` from the repository root as a user would; its stdout."""
    command = [sys.executable, str(EXAMPLES / script), *args]
    done = subprocess.run(command, capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_every_example_is_run_by_a_test():
    tests = "\n".join(path.read_text() for path in (ROOT / "tests").rglob("test_*.py"))
    for script in sorted(EXAMPLES.glob("*.py")):
        if script.name != "__init__.py":
            assert script.name in tests or f"examples.{script.stem}" in tests, script.name


@pytest.mark.slow
def test_custom_world_is_driven_and_a_broken_copy_refused(tmp_path):
    out = run("custom_world.py", "--out", str(tmp_path))
    assert (tmp_path / "u_corridor.yaml").is_file()
    assert "'reached_goal': True" in out and "'collision': False" in out
    assert re.search(r"broken\.yaml: world\.landmarks\[0\]\.at must lie on a wall", out)


@pytest.mark.slow
def test_train_and_evaluate_round_trip(tmp_path):
    out = run("train_and_evaluate.py", "--out", str(tmp_path))
    assert (tmp_path / "ppo-truth" / "model.zip").is_file()
    assert (tmp_path / "ppo-truth" / "train.json").is_file()
    for agent in ("follower", "model"):
        assert (tmp_path / f"evaluate-{agent}" / "results.json").is_file()
        line = rf"^{agent}: (reached the goal|cut at the 10 s time limit after [\d.]+ m), ATE \d"
        assert re.search(line, out, re.MULTILINE), out


@pytest.mark.slow
def test_animation_of_an_episode(tmp_path):
    path = tmp_path / "short.gif"
    run("animate_episode.py", "--seconds", "4", "--camera", "fast", "--out", str(path))
    with Image.open(path) as gif:
        assert gif.n_frames == 3  # t = 0, 1.5 and 3 s
        assert gif.size == (480, 360)


def test_animation_frames_show_both_estimates():
    from examples.animate_episode import frames
    from stsf_gym.envs.rendering.map_view import ESTIMATE_COLOURS

    last = frames(2.0, 1.0, "fast", seed=0)[-1].astype(int)
    for colour in ESTIMATE_COLOURS[:2]:  # STSF's (the wrapper's) and odometry's
        assert (np.abs(last - colour).sum(axis=-1) < 10).sum() > 10, colour  # legend and marker
