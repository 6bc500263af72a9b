"""``stsf-gym bench``: each case measures in its own process; targets are judged correctly."""

from __future__ import annotations

import pytest
from helpers import ROOT

from stsf_gym.bench.report import to_markdown
from stsf_gym.bench.speed import run_case
from stsf_gym.bench.targets import targets
from stsf_gym.validation import ConfigError


@pytest.fixture(scope="module")
def fast_row():
    return run_case("g: fast sensor mode + STSF", sim_seconds=3.0)


def test_a_case_reports_speed_memory_and_stage_latency(fast_row):
    assert fast_row["renderer"] == "none"
    assert fast_row["steps"] == 30
    assert fast_row["x_real_time"] > 0 and fast_row["peak_rss_mb"] > 10
    assert fast_row["x_real_time_cpu"] == pytest.approx(3.0 / fast_row["cpu_s"])
    assert fast_row["camera_frames"] == 15  # 5 Hz over 3 s
    assert fast_row["renders_per_frame"] == 0  # detections simulated, nothing rendered
    assert set(fast_row["ms_per_frame"]) == {"camera frame", "detect", "stsf update"}
    assert "detector_vs_aruco" not in fast_row  # no images in the fast mode
    assert fast_row["estimator_ms_per_step"] > 0


def _summary(row: dict, **changes) -> dict:
    cases = ("a: x", "e: x", "f: x", "g: x", "h: x", "i: x", "j: x")
    rows = [{**row, "case": name, **changes} for name in cases]
    rows[1]["ms_per_frame"] = {"detect": 1.5, "stsf update": 0.4, "camera frame": 3.0}
    rows[1]["renders_per_frame"] = 2.5
    rows[1]["detector_vs_aruco"] = {
        "frames": 3,
        "detector_ms": 1.5,
        "pipeline_ms": 2.0,
        "aruco_ms": 1.0,
        "ratio": 1.5,
        "pipeline_ratio": 2.0,
    }
    rows[1]["renderer"] = "gl"
    rows[2]["ms_per_frame"] = {"detect": 1.5, "ekf update": 0.1}
    rows[4]["ms_per_frame"] = {"detect": 0.2, "ekf update": 0.1}
    rows[5]["ms_per_frame"] = {"detect": 0.2, "smoother update": 2.5}
    rows[6]["estimator_ms_per_step"] = 1.0
    return {
        "machine": {"cpu": "test", "cores": 2, "python": "3", "reference_ms": 50.0},
        "process": {
            "import_env_s": 0.5,
            "import_env_references": 10.0,
            "import_training_s": 4.0,
            "import_training_references": 80.0,
            "first_step_s": 4.5,
            "first_step_references": 90.0,
        },
        "speed": rows,
        "render": [
            {
                "renderer": "gl",
                "ms_320x240": 1.5,
                "camera_frame_ms_320x240": 2.0,
                "ms_640x480": 4.5,
                "camera_frame_ms_640x480": 10.0,
                "peak_rss_mb": 99,
            }
        ],
        "vector": [
            {
                "pipeline": pipeline,
                "vector env": kind,
                "steps_per_s_1_worker": 100.0,
                "steps_per_s_2_workers": rate,
                "speed_up": rate / 100,
                "worker_cpu_ms_per_step_1_worker": 7.0,
                "wall_ms_per_step_1_worker": 5.0,
                "wall_ms_per_step_2_workers": 2000 / rate,
                "worker_cpu_ms_per_step_2_workers": 8.0,
                "parent_cpu_ms_per_step_2_workers": 1.0,
            }
            for pipeline, rate in (("rendered STSF", 160.0), ("fast mode STSF", 190.0))
            for kind in ("AsyncVectorEnv", "SubprocVecEnv")
        ],
    }


def test_targets_are_judged_against_their_bounds(fast_row):
    summary = _summary(fast_row, x_real_time_cpu=120.0, peak_rss_mb=350.0)
    summary["speed"][1]["x_real_time_cpu"] = 30.0  # e: 0.25 of camera off (CPU time)
    judged = {t["target"]: t for t in targets(summary)}
    met = {name: t["met"] for name, t in judged.items()}
    assert summary["speed"][1]["vs_camera_off"] == 0.25
    assert summary["speed"][0]["sim_s_per_reference"] == 120.0 * 0.05
    assert not met["e: camera + detector + STSF / camera off"]  # 0.25 < 0.3
    assert "detect 1.50 ms" in judged["e: camera + detector + STSF / camera off"]["reason"]
    assert met["f: camera + detector + EKF / camera off"]  # 1.0
    assert met["g: fast sensor mode + STSF / camera off"]
    assert not met["detection with track-aided matching / ArUco detectMarkers, same frames"]
    assert met["detector / ArUco time (plain detector)"]
    frame_target = "camera frame 320x240 (render, lens, defocus, blur, sensor), ms"
    assert not met[frame_target]  # 3 > 1.5
    assert "2.50 renders a frame" in judged[frame_target]["reason"]
    assert "a still frame (one render) takes 2.00 ms" in judged[frame_target]["reason"]
    assert not met["camera frame 640x480 / plain GL render 640x480"]  # 10 / 4.5 > 2
    assert met["GL render 320x240, ms per frame"]  # 1.5 <= 2
    assert not met["GL render 640x480, ms per frame"]  # 4.5 > 4
    assert not met["2 workers / 1 worker, AsyncVectorEnv, rendered STSF"]  # 1.6 < 1.8
    assert met["2 workers / 1 worker, SubprocVecEnv, fast mode STSF"]  # 1.9
    vector_reason = judged["2 workers / 1 worker, AsyncVectorEnv, rendered STSF"]["reason"]
    split = "12.50 ms wall = a worker's 8.00 ms CPU + the parent's 1.00 ms + 3.50 ms"
    assert split in vector_reason
    assert "one worker alone: 7.00 ms CPU per step in 5.00 ms wall (1.40 cores" in vector_reason
    assert not met["peak memory per GL-camera env process, MB"]  # 350 > 250
    assert all(t["reason"] == "" for t in judged.values() if t["met"] and t["bound"] != "-")
    assert not met["smoother update, ms per camera frame"]  # 2.5 > 2
    assert met["MCL, ms per step (every stage)"]  # 1.0 <= 3
    assert met["import stsf_gym, reference workloads"]  # 10 <= 20
    assert not met["import the training stack, reference workloads"]  # 80 > 60
    assert "torch" in judged["import the training stack, reference workloads"]["reason"]
    assert met["first step of STSF (make, reset, step), reference workloads"]  # 90 <= 100
    summary["targets"] = targets(summary)
    text = to_markdown(summary)
    assert "ratios 1.50 and 2.00" in text
    assert "| 2 workers / 1 worker, SubprocVecEnv, rendered STSF |" in text
    assert "Reference workload (fixed Python + numpy work, best of 3): 50.0 ms" in text
    assert "the first step of STSF (make, reset, step) 4.50 s" in text


def test_recording_targets_are_judged(fast_row):
    summary = _summary(fast_row, x_real_time_cpu=120.0)
    row = {"distance_m": 24.0, "episode_cpu_s": 10.0, "recorded_cpu_s": 11.0, "size_mb": 30.0}
    summary["recording"] = {
        "recordings": [
            {**row, "mode": "fast", "format": "mcap", "frames": "-", "overhead": 0.08},
            {**row, "mode": "fast", "format": "rerun", "frames": "-", "overhead": 0.12},
            {**row, "mode": "rendered", "format": "mcap", "frames": "jpeg", "overhead": 0.05},
            {**row, "mode": "rendered", "format": "mcap", "frames": "png", "overhead": 0.9},
        ],
        "replays": [
            {"mode": "rendered", "episode_cpu_s": 10.0, "replay_cpu_s": 2.0, "speed_up": 5.0}
        ],
        "import_cpu_s": {"mcap_writer": 0.3, "rerun_writer": 0.5},
    }
    met = {t["target"]: t["met"] for t in targets(summary)}
    assert not met["recording overhead, fast mode (costlier of MCAP, Rerun), %"]  # 12 % > 10
    assert met["recording overhead, rendered (costliest of raw, JPEG, Rerun), %"]  # PNG not judged
    assert met["MCAP of a 24 m rendered episode, JPEG, MB"]
    assert met["rendered replay (STSF) / live episode speed"]
    summary["targets"] = targets(summary)
    text = to_markdown(summary)
    assert "## Recording" in text and "mcap_writer 0.30, rerun_writer 0.50" in text


@pytest.mark.slow
def test_the_step_section_runs_side_by_side_with_a_checkout(tmp_path):
    """The step cases on this code and on a checkout (this one, laid out as installed): both
    measured in fresh processes, the ratio of this code over it, the section in bench.md."""

    from stsf_gym.bench import run_step_bench
    from stsf_gym.bench.step import CASES

    checkout = ROOT
    summary = run_step_bench(tmp_path, steps=5, baseline=checkout, rounds=2)
    rows = summary["step"]["rows"]
    assert [r["case"] for r in rows] == list(CASES)
    for row in rows:
        assert row["this"] > 0 and row["baseline"] > 0
        assert row["ratio"] == pytest.approx(row["this"] / row["baseline"])
        assert row["ratio_cpu"] == pytest.approx(row["this_cpu"] / row["baseline_cpu"])
        # each segment's fastest round, summed, is at least as fast as the fastest round
        for side in ("this", "baseline"):
            assert row[f"{side}_segments"] >= row[side] * (1 - 1e-12)
        segments = row["this_segments"] / row["baseline_segments"]
        assert row["ratio_segments"] == pytest.approx(segments)
        assert row["ratio_rounds"]["count"] == 2 and min(row["ratio_rounds"]["values"]) > 0
    # each follower case profiled once per code, its stages nested as they run
    profiles = {(p["case"], p["side"]): p for p in summary["step"]["profiles"]}
    followed = [case for case in CASES if case.endswith("follower")]
    assert set(profiles) == {(case, side) for case in followed for side in ("this", "baseline")}
    for (case, _), profile in profiles.items():
        ms = profile["stages_ms"]
        assert ms["physics"] + ms["sonar"] + ms["fast camera"] <= ms["env step"]
        assert ms["env step"] < ms["pose wrapper"] <= profile["step_ms"]
        assert ms["estimator, frames"] <= ms["estimator, update"]
        assert (ms["estimator, update"] > 0) == case.startswith("stsf")
    text = (tmp_path / "bench.md").read_text()
    assert "Env steps per second" in text and "Where a step goes: stsf, fast camera" in text


def test_a_baseline_that_is_no_checkout_is_refused(tmp_path):
    from stsf_gym.bench.step import check_baseline

    with pytest.raises(ConfigError, match="neither a Python interpreter nor a checkout"):
        check_baseline(tmp_path)


def test_a_measured_case_times_its_steps_in_segments():
    """The timed steps come in SEGMENT_STEPS pieces, the last one shorter; their wall times
    add up to the steps/s reported."""
    from stsf_gym.bench.step import SEGMENT_STEPS, measure

    row = measure("truth, camera off, follower", steps=2 * SEGMENT_STEPS + 30, warmup=5)
    assert len(row["segment_s"]) == 3 and min(row["segment_s"]) > 0
    assert row["steps_per_s"] == pytest.approx(row["steps"] / sum(row["segment_s"]))


@pytest.mark.slow
def test_process_costs_are_measured_in_fresh_processes():
    from stsf_gym.bench.process_cost import process_costs

    costs = process_costs(reference_ms=50.0, rounds=1)
    assert 0 < costs["import_env_s"] < costs["first_step_s"]
    assert costs["import_training_s"] > 0
    assert costs["first_step_references"] == 1e3 * costs["first_step_s"] / 50.0


# --- a baseline that says nothing ------------------------------------------------------------


def test_a_baseline_that_exits_0_saying_nothing_is_refused(run_cli, tmp_path):
    true = tmp_path / "true"  # as /bin/true: any arguments, exit 0, no output
    true.write_text("#!/bin/sh\nexit 0\n")
    true.chmod(0o755)
    code, err = run_cli(
        "bench", "--step-only", "--baseline", str(true), "--out", str(tmp_path / "o")
    )
    assert code == 2 and err.strip().endswith("exited 0 and printed nothing)")
    assert not (tmp_path / "o").exists()
