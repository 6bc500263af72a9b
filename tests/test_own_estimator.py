"""Your own estimator wherever a pose-source name is taken: ``package.module:Class`` with its
settings dataclass's defaults, keyword options over them, and ``register_estimator``."""

import json
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import pytest

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.estimators import ESTIMATORS, make_estimator, register_estimator
from stsf_gym.results import check_rows
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import check_pose_source

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = "examples.complementary:ComplementaryFilter"


def test_example_through_the_cli(tmp_path):
    """The console script (not ``python -m``) imports the example from the working directory."""
    script = Path(sys.executable).parent / "stsf-gym"
    result = subprocess.run(
        [
            str(script),
            "evaluate",
            "--estimators",
            f"odometry,{EXAMPLE}",
            "--seeds",
            "1",
            "--workers",
            "1",
            "--set",
            "camera.mode=fast",
            "--set",
            "sim.max_episode_seconds=40",
            "--out",
            str(tmp_path),
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert result.returncode == 0, result.stderr
    rows = {row["estimator"]: row for row in json.loads(result.stdout)["rows"]}
    check_rows(list(rows.values()))
    assert set(rows) == {"odometry", EXAMPLE}
    # the boards pull the example back; dead reckoning drifts with the calibration error
    assert rows[EXAMPLE]["match_rate"]["mean"] > 0.5
    assert rows[EXAMPLE]["ate_rmse_m"]["mean"] < 0.05


def test_defaults_and_options_checked():
    assert make_estimator(EXAMPLE).settings.gain == 0.2
    assert make_estimator(EXAMPLE, gain=0.5).settings.gain == 0.5
    with pytest.raises(ConfigError, match="gain"):
        make_estimator(EXAMPLE, gain=2.0)
    with pytest.raises(ConfigError, match="unknown config key"):
        make_estimator(EXAMPLE, gian=0.5)


def test_gym_make_with_own_estimator():
    env = gym.make("stsf_gym/Corridor-EKF-v0", estimator=EXAMPLE, camera__mode="fast")
    obs, _ = env.reset(seed=0)
    assert type(env.get_wrapper_attr("estimator")).__name__ == "ComplementaryFilter"
    assert obs["pose"].shape == (3,)
    env.close()


def test_register_and_bad_names():
    register_estimator("complementary-example", EXAMPLE)
    try:
        assert type(make_estimator("complementary-example")).__name__ == "ComplementaryFilter"
        check_pose_source("complementary-example")
        with pytest.raises(ValueError, match="taken"):
            register_estimator("ekf", EXAMPLE)
    finally:
        del ESTIMATORS["complementary-example"]
    for bad in ("no_such_estimator", "stsf_gym.geometry:wrap_angle", "nosuch.module:Class"):
        with pytest.raises(ConfigError, match="estimator"):
            check_pose_source(bad)
