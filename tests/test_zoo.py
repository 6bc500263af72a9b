"""rl-zoo3 runs on the registered ids with ``--conf-file stsf_gym.agents.zoo``."""

import os
import re
import subprocess
import sys
from pathlib import Path

from stsf_gym.agents.zoo import hyperparams, zoo_section

ROOT = Path(__file__).resolve().parents[1]


def test_sections_follow_the_training_config():
    assert "stsf_gym/Corridor-STSF-v0" in hyperparams
    assert "stsf_gym/Straight10m-Truth-v0" in hyperparams
    assert "stsf_gym/Corridor-v0" not in hyperparams  # no estimate: no policy observation
    truth = zoo_section("ppo", "stsf_gym/Corridor-Truth-v0")
    assert truth["env_kwargs"]["camera"] == {"mode": "fast", "enabled": False}
    assert truth["policy"] == "MlpPolicy" and truth["n_steps"] == 1024


def test_rl_zoo3_trains_ppo_through_gym_packages(tmp_path):
    command = [sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo"]
    command += ["--env", "stsf_gym/Straight10m-Truth-v0", "--gym-packages", "stsf_gym"]
    command += [
        "--conf-file",
        "stsf_gym.agents.zoo",
        "-n",
        "128",
        "--seed",
        "0",
        "--eval-freq",
        "-1",
    ]
    command += ["-f", str(tmp_path), "-params", "n_envs:1", "n_steps:64", "batch_size:32"]
    command += ["--eval-env-kwargs", "camera:{'enabled':False}"]
    result = subprocess.run(
        command,
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    assert re.search(r"total_timesteps\s*\|\s*128\b", result.stdout), result.stdout[-2000:]
    (model,) = tmp_path.glob("ppo/stsf_gym-Straight10m-Truth-v0_1/*.zip")
    assert model.stat().st_size > 10_000
