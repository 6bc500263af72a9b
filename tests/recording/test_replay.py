"""``stsf-gym evaluate --record mcap`` then ``stsf-gym replay``: the evaluation's numbers again,
with no simulator loaded; evo, which we did not write, reads the log's poses."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from evo.core import metrics
from evo.tools import file_interface
from helpers import ROOT
from rosbags.rosbag2 import Reader

from stsf_gym.cli import main
from stsf_gym.recording import topics

EPISODE = ["--set", "camera.mode=fast", "--set", "sim.max_episode_seconds=8", "--seeds", "1"]

REPLAY = """
import json, sys
from stsf_gym.cli import main
code = main(sys.argv[2:])
with open(sys.argv[1], "w") as f:
    json.dump({"code": code, "modules": sorted(sys.modules)}, f)
"""

MODULES = """
import json, sys
import stsf_gym.experiments.replay, stsf_gym.recording.log_reader, stsf_gym.recording.replay
print(json.dumps(sorted(sys.modules)))
"""


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory):
    out = tmp_path_factory.mktemp("evaluate")
    args = ["evaluate", "--estimators", "stsf", "--workers", "1", "--out", str(out), *EPISODE]
    assert main([*args, "--record", "mcap", "--json"]) == 0
    return out


@pytest.mark.slow
def test_replay_gives_the_evaluation_again_without_the_simulator(evaluated, tmp_path):
    (log,) = sorted((evaluated / "recordings").glob("*.mcap"))
    report = tmp_path / "modules.json"
    args = ["replay", str(log), "--estimators", "stsf,odometry", "--out", str(tmp_path / "r")]
    subprocess.run([sys.executable, "-c", REPLAY, str(report), *args], cwd=ROOT, check=True)
    done = json.loads(report.read_text())
    assert done["code"] == 0
    simulator = [m for m in done["modules"] if m.startswith(("pybullet", "stsf_gym.envs.sim"))]
    assert not simulator and "stsf_gym.envs.corridor_env" not in done["modules"]
    live = json.loads((evaluated / "results.json").read_text())["rows"][0]
    replayed = json.loads((tmp_path / "r" / "results.json").read_text())["rows"]
    stsf = next(row for row in replayed if row["estimator"] == "stsf")
    for key in ("ate_rmse_m", "final_error_m", "nees_mean", "match_rate", "success_rate"):
        assert stsf[key]["values"] == live[key]["values"], key
    assert stsf["recorded_difference_m"] == 0.0 and stsf["approximate"] is False
    assert (tmp_path / "r" / "trajectories" / f"{log.stem}-odometry" / "estimate.txt").is_file()


@pytest.mark.slow
def test_the_replay_modules_load_no_simulator_module():
    done = subprocess.run(
        [sys.executable, "-c", MODULES], capture_output=True, text=True, cwd=ROOT, check=True
    )
    loaded = [m for m in json.loads(done.stdout) if m.startswith(("stsf_gym.envs", "pybullet"))]
    assert not loaded, f"replay loaded the simulator side: {loaded}"


def test_evo_reads_the_log_and_its_ape_is_our_ate(evaluated):
    (log,) = sorted((evaluated / "recordings").glob("*.mcap"))
    with Reader(log) as reader:
        truth = file_interface.read_bag_trajectory(reader, topics.TRUTH)
        estimate = file_interface.read_bag_trajectory(reader, topics.estimate_topic("stsf"))
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((truth, estimate))
    ours = json.loads((evaluated / "results.json").read_text())["rows"][0]["ate_rmse_m"]["mean"]
    # the evaluation scores the float32 pose the agent saw, the log holds the float64 estimate
    assert ape.get_statistic(metrics.StatisticsType.rmse) == pytest.approx(ours, abs=1e-6)


def test_replay_names_a_bad_log(tmp_path):
    bad = tmp_path / "empty.mcap"
    bad.write_bytes(b"not an mcap file")
    assert main(["replay", str(bad), "--out", str(tmp_path / "r")]) == 2
    assert main(["replay", str(tmp_path / "missing.mcap"), "--out", str(tmp_path / "r")]) == 2
    assert not (tmp_path / "r" / "results.json").exists()


def test_benchmark_records_its_episodes(tmp_path):
    args = ["benchmark", "--suite", "corridor", "--worlds", "1", "--estimators", "odometry"]
    assert (
        main([*args, "--workers", "1", "--record", "mcap", "--out", str(tmp_path), "--json"]) == 0
    )
    (log,) = sorted((tmp_path / "corridor" / "recordings").glob("*.mcap"))
    assert ":" not in log.name
    assert main(["replay", str(log), "--estimators", "odometry", "--out", str(tmp_path / "r")]) == 0
    row = json.loads((tmp_path / "r" / "results.json").read_text())["rows"][0]
    assert row["recorded_difference_m"] == 0.0
