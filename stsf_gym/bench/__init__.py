"""``stsf-gym bench``: the speed figures, each beside its target, in one run.

1. Env speed as a multiple of real time on one core (cases a-e of :mod:`.speed`), with the
   renderer named and the peak memory of each env process.
2. Latency per camera frame of each stage (render, detection, motion stereo + STSF update,
   EKF update) beside the paper's 0.127 s to detect and 0.332 s to localise, and the detector
   beside OpenCV's ArUco ``detectMarkers`` on the same frames.
3. ``AsyncVectorEnv`` throughput with 1 and 2 workers.
4. Where the time goes: cProfile's top functions over the camera pipeline (case d).

Writes ``bench.json`` and ``bench.md`` to the output folder.
"""

from __future__ import annotations

import os
import platform
from pathlib import Path

from tqdm import tqdm

from stsf_gym.bench.speed import CASES, run_case, vector_scaling
from stsf_gym.io import markdown_table, write_atomic, write_json

PAPER_MS = {"detect": 127.0, "localise": 332.0}  # sect. 4.3, 1 GHz Pentium IV
PROFILED_CASE = "d: camera + detector + STSF"


def machine() -> dict:
    cpu = platform.processor() or platform.machine()
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        names = [
            ln.split(":", 1)[1].strip()
            for ln in cpuinfo.read_text().splitlines()
            if ln.startswith("model name")
        ]
        cpu = names[0] if names else cpu
    return {"cpu": cpu, "cores": os.cpu_count(), "python": platform.python_version()}


def run_bench(out: Path, sim_seconds: float = 60.0, vector_steps: int = 1000, seed: int = 0):
    """Run every measurement; write bench.json / bench.md; return the summary."""
    speed = []
    for name in tqdm(CASES, desc="bench cases", unit="case"):
        fast_case = name.startswith(("a:", "e:"))
        seconds = sim_seconds * (4 if fast_case else 1)  # fast cases: a longer, steadier span
        speed.append(run_case(name, seconds, seed, profile=name == PROFILED_CASE))
    vector = vector_scaling(vector_steps, seed)
    summary = {"machine": machine(), "speed": speed, "vector": vector}
    summary["targets"] = targets(summary)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "bench.json", summary)
    write_atomic(out / "bench.md", to_markdown(summary))
    return summary


def _row(summary: dict, prefix: str) -> dict:
    return next(r for r in summary["speed"] if r["case"].startswith(prefix))


def targets(summary: dict) -> list[dict]:
    """Each target of the speed issue with what was measured and whether it holds."""
    stsf = _row(summary, "d:")
    ekf = _row(summary, "camera + detector + EKF")
    aruco = stsf.get("detector_vs_aruco", {})
    checks = [
        ("a: camera off, x real time", _row(summary, "a:")["x_real_time"], ">=", 100),
        ("d: full pipeline, x real time", stsf["x_real_time"], ">=", 10),
        ("e: fast sensor mode, x real time", _row(summary, "e:")["x_real_time"], ">=", 50),
        ("2 workers / 1 worker", summary["vector"]["speed_up"], ">=", 1.7),
        ("detection, ms per frame", stsf["ms_per_frame"]["detect"], "<", 2.0),
        ("STSF update, ms per frame", stsf["ms_per_frame"]["stsf update"], "<", 0.5),
        ("detector / ArUco time", aruco.get("ratio", float("nan")), "<=", 2.0),
        (
            "peak memory per env process, MB",
            max(r["peak_rss_mb"] for r in summary["speed"]),
            "<=",
            300,
        ),
        ("EKF update, ms per frame (no target)", ekf["ms_per_frame"]["ekf update"], "<", 1e9),
    ]
    return [
        {
            "target": name,
            "measured": value,
            "bound": f"{op} {bound:g}",
            "met": bool(
                value >= bound if op == ">=" else value <= bound if op == "<=" else value < bound
            ),
        }
        for name, value, op, bound in checks
    ]


def to_markdown(summary: dict) -> str:
    m = summary["machine"]
    speed_rows = [
        {
            "case": r["case"],
            "renderer": r["renderer"],
            "x real time": r["x_real_time"],
            "steps/s": r["steps_per_s"],
            "peak MB": r["peak_rss_mb"],
        }
        for r in summary["speed"]
    ]
    stsf = _row(summary, "d:")
    ekf = _row(summary, "camera + detector + EKF")
    frame = stsf["ms_per_frame"]
    latency_rows = [
        {"stage": "render (EGL)", "ms per frame": frame.get("render"), "paper ms": None},
        {
            "stage": "landmark detection",
            "ms per frame": frame["detect"],
            "paper ms": PAPER_MS["detect"],
        },
        {
            "stage": "motion stereo + STSF update",
            "ms per frame": frame["stsf update"],
            "paper ms": PAPER_MS["localise"],
        },
        {
            "stage": "EKF update",
            "ms per frame": ekf["ms_per_frame"]["ekf update"],
            "paper ms": None,
        },
    ]
    parts = [
        f"# stsf-gym bench\n\n{m['cpu']}, {m['cores']} cores, Python {m['python']}; "
        "each speed case in its own process pinned to one core.\n",
        "## Env speed (IRL corridor, follower driving)\n\n" + markdown_table(speed_rows),
        "## Latency per camera frame (320x240)\n\n" + markdown_table(latency_rows),
    ]
    if "detector_vs_aruco" in stsf:
        a = stsf["detector_vs_aruco"]
        parts.append(
            f"Detector {a['detector_ms']:.3f} ms vs ArUco detectMarkers {a['aruco_ms']:.3f} ms "
            f"per frame on the same {a['frames']} frames: ratio {a['ratio']:.2f}.\n"
        )
    v = summary["vector"]
    parts.append(
        "## AsyncVectorEnv (fast-mode STSF pipeline)\n\n"
        f"1 worker {v['steps_per_s_1_worker']:.0f} steps/s, 2 workers "
        f"{v['steps_per_s_2_workers']:.0f} steps/s: {v['speed_up']:.2f}x.\n"
    )
    if "profile" in stsf:
        rows = [{**p, "own_share": f"{100 * p['own_share']:.1f} %"} for p in stsf["profile"]]
        parts.append(f"## Where the time goes ({PROFILED_CASE})\n\n" + markdown_table(rows))
    parts.append("## Targets\n\n" + markdown_table(summary["targets"]))
    return "\n".join(parts)
