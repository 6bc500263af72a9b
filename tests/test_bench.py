"""``stsf-gym bench``: each case measures in its own process; targets are judged correctly."""

import pytest

from stsf_gym.bench import targets, to_markdown
from stsf_gym.bench.speed import run_case


@pytest.fixture(scope="module")
def fast_row():
    return run_case("g: fast sensor mode + STSF", sim_seconds=3.0)


def test_a_case_reports_speed_memory_and_stage_latency(fast_row):
    assert fast_row["renderer"] == "none"
    assert fast_row["steps"] == 30
    assert fast_row["x_real_time"] > 0 and fast_row["peak_rss_mb"] > 10
    assert fast_row["camera_frames"] == 15  # 5 Hz over 3 s
    assert set(fast_row["ms_per_frame"]) == {"camera frame", "detect", "stsf update"}
    assert "detector_vs_aruco" not in fast_row  # no images in the fast mode
    assert fast_row["estimator_ms_per_step"] > 0


def _summary(row: dict, **changes) -> dict:
    cases = ("a: x", "e: x", "f: x", "g: x", "h: x", "i: x", "j: x")
    rows = [{**row, "case": name, **changes} for name in cases]
    rows[1]["ms_per_frame"] = {"detect": 1.5, "stsf update": 0.4, "camera frame": 3.0}
    rows[1]["detector_vs_aruco"] = {"frames": 3, "detector_ms": 1.5, "aruco_ms": 1.0, "ratio": 1.5}
    rows[1]["renderer"] = "gl"
    rows[2]["ms_per_frame"] = {"detect": 1.5, "ekf update": 0.1}
    rows[4]["ms_per_frame"] = {"detect": 0.2, "ekf update": 0.1}
    rows[5]["ms_per_frame"] = {"detect": 0.2, "smoother update": 2.5}
    rows[6]["estimator_ms_per_step"] = 1.0
    return {
        "machine": {"cpu": "test", "cores": 2, "python": "3", "reference_ms": 50.0},
        "speed": rows,
        "render": [{"renderer": "gl", "ms_320x240": 1.5, "ms_640x480": 4.5, "peak_rss_mb": 99}],
        "vector": {"steps_per_s_1_worker": 100.0, "steps_per_s_2_workers": 160.0, "speed_up": 1.6},
    }


def test_targets_are_judged_against_their_bounds(fast_row):
    summary = _summary(fast_row, x_real_time=120.0, peak_rss_mb=350.0)
    met = {t["target"]: t["met"] for t in targets(summary)}
    assert met["a: camera off, x real time"] and met["e: camera + detector + STSF, x real time"]
    assert met["detection, ms per frame"] and met["detector / ArUco time"]
    assert met["GL render 320x240, ms per frame"]  # 1.5 <= 2
    assert not met["GL render 640x480, ms per frame"]  # 4.5 > 4
    assert not met["2 workers / 1 worker (rendered pipeline)"]  # 1.6 < 1.7
    assert not met["peak memory per GL-camera env process, MB"]  # 350 > 250
    assert not met["smoother update, ms per camera frame"]  # 2.5 > 2
    assert met["MCL, ms per step (every stage)"]  # 1.0 <= 3
    summary["targets"] = targets(summary)
    text = to_markdown(summary)
    assert "ratio 1.50" in text and "| 2 workers / 1 worker (rendered pipeline) |" in text
    assert "Reference workload (fixed Python + numpy work, best of 3): 50.0 ms" in text


def test_recording_targets_are_judged(fast_row):
    summary = _summary(fast_row, x_real_time=120.0)
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
