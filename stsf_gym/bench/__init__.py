"""``stsf-gym bench``: the speed figures, each beside its target, in one run.

1. Env speed as a multiple of real time on one core (cases a-g of :mod:`.speed`), with the
   renderer named and the peak memory of each env process.
2. Each renderer alone (GL, PyBullet's EGL, TinyRenderer): ms per frame at 320x240 and
   640x480 on one core.
3. Latency per camera frame of each stage (camera frame: render, lens and sensor; detection,
   motion stereo + STSF update, EKF update) beside the paper's 0.127 s to detect and 0.332 s
   to localise, and the detector beside OpenCV's ArUco ``detectMarkers`` on the same frames.
4. ``AsyncVectorEnv`` throughput of the rendered STSF pipeline with 1 and 2 workers.
5. Where the time goes: cProfile's top functions over the camera pipeline (case e).
6. Recording (:mod:`.recording`): what ``--record`` adds to an episode's wall time, the files'
   sizes, and how much faster a replay of a recorded episode runs than the episode itself.

Writes ``bench.json`` and ``bench.md`` to the output folder.
"""

from __future__ import annotations

import os
import platform
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from stsf_gym.bench.recording import recording_costs
from stsf_gym.bench.speed import CASES, FAST_CASES, render_latency, run_case, vector_scaling
from stsf_gym.io import markdown_table, write_atomic, write_json
from stsf_gym.results.provenance import provenance

PAPER_MS = {"detect": 127.0, "localise": 332.0}  # sect. 4.3, 1 GHz Pentium IV
PROFILED_CASE = "e: camera + detector + STSF"


def machine() -> dict:
    """The machine: CPU model, cores, Python version and the reference workload's time (ms)."""
    cpu = platform.processor() or platform.machine()
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        names = [
            ln.split(":", 1)[1].strip()
            for ln in cpuinfo.read_text().splitlines()
            if ln.startswith("model name")
        ]
        cpu = names[0] if names else cpu
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "reference_ms": reference_ms(),
    }


def reference_ms() -> float:
    """Milliseconds of a fixed Python + numpy workload (best of 3): the machine's speed at the
    time of the run, so figures from runs on a busy or throttled machine can be told apart."""

    def work() -> None:
        sum(i * i for i in range(300_000))
        a = np.random.default_rng(0).standard_normal((200, 200))
        for _ in range(20):
            a = np.tanh(a @ a.T / 200)

    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        work()
        best = min(best, time.perf_counter() - start)
    return 1000 * best


def run_bench(out: Path, sim_seconds: float = 60.0, vector_steps: int = 1000, seed: int = 0):
    """Run every measurement; write bench.json / bench.md; return the summary."""
    speed = []
    for name in tqdm(CASES, desc="bench cases", unit="case"):
        fast_case = name.startswith(FAST_CASES)
        seconds = sim_seconds * (4 if fast_case else 1)  # fast cases: a longer, steadier span
        speed.append(run_case(name, seconds, seed, profile=name == PROFILED_CASE))
    renders = render_latency()
    vector = vector_scaling(vector_steps, seed)
    recording = recording_costs(seed)
    summary = {
        "machine": machine(),
        "speed": speed,
        "render": renders,
        "vector": vector,
        "recording": recording,
    }
    summary["targets"] = targets(summary)
    summary["provenance"] = provenance({"sim_seconds": sim_seconds, "vector_steps": vector_steps})
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "bench.json", summary)
    write_atomic(out / "bench.md", to_markdown(summary))
    return summary


def _row(summary: dict, prefix: str) -> dict:
    return next(r for r in summary["speed"] if r["case"].startswith(prefix))


def targets(summary: dict) -> list[dict]:
    """Each speed target with what was measured and whether it holds."""
    stsf = _row(summary, "e:")
    ekf = _row(summary, "f:")
    fast_ekf, smoother, mcl = (_row(summary, case) for case in ("h:", "i:", "j:"))
    aruco = stsf.get("detector_vs_aruco", {})
    gl = next((r for r in summary["render"] if r["renderer"] == "gl"), {})
    nan = float("nan")
    gl_cases = [r["peak_rss_mb"] for r in summary["speed"] if r["renderer"] == "gl"]
    checks = [
        ("GL render 320x240, ms per frame", gl.get("ms_320x240", nan), "<=", 2.0),
        ("GL render 640x480, ms per frame", gl.get("ms_640x480", nan), "<=", 4.0),
        ("a: camera off, x real time", _row(summary, "a:")["x_real_time"], ">=", 100),
        ("e: camera + detector + STSF, x real time", stsf["x_real_time"], ">=", 30),
        ("f: camera + detector + EKF, x real time", ekf["x_real_time"], ">=", 30),
        ("g: fast sensor mode, x real time", _row(summary, "g:")["x_real_time"], ">=", 50),
        ("2 workers / 1 worker (rendered pipeline)", summary["vector"]["speed_up"], ">=", 1.7),
        ("detection, ms per frame", stsf["ms_per_frame"]["detect"], "<", 2.0),
        ("STSF update, ms per frame", stsf["ms_per_frame"]["stsf update"], "<", 0.5),
        ("detector / ArUco time", aruco.get("ratio", nan), "<=", 2.0),
        ("peak memory per GL-camera env process, MB", max(gl_cases, default=nan), "<=", 250),
        ("EKF update, ms per frame (no target)", ekf["ms_per_frame"]["ekf update"], "<", 1e9),
        (
            "smoother update, ms per camera frame",
            smoother["ms_per_frame"]["smoother update"],
            "<=",
            2.0,
        ),
        ("MCL, ms per step (every stage)", mcl["estimator_ms_per_step"], "<=", 3.0),
        ("EKF, ms per step (every stage, no target)", fast_ekf["estimator_ms_per_step"], "<", 1e9),
    ]
    if "recording" in summary:
        checks += recording_checks(summary["recording"])
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


def recording_checks(recording: dict) -> list[tuple[str, float, str, float]]:
    """The recording targets: overhead per sensor mode (the costliest format but PNG frames),
    the JPEG MCAP's size, and the rendered replay's speed-up."""
    rows = recording["recordings"]

    def worst(mode: str) -> float:  # PNG frames, an option slow to encode, are not judged
        return 100 * max(r["overhead"] for r in rows if r["mode"] == mode and r["frames"] != "png")

    jpeg = next(r for r in rows if r["mode"] == "rendered" and r["frames"] == "jpeg")
    replayed = next(r for r in recording["replays"] if r["mode"] == "rendered")
    return [
        ("recording overhead, fast mode (costlier of MCAP, Rerun), %", worst("fast"), "<=", 10),
        (
            "recording overhead, rendered (costliest of raw, JPEG, Rerun), %",
            worst("rendered"),
            "<=",
            15,
        ),
        (
            f"MCAP of a {jpeg['distance_m']:.0f} m rendered episode, JPEG, MB",
            jpeg["size_mb"],
            "<=",
            50,
        ),
        ("rendered replay (STSF) / live episode speed", replayed["speed_up"], ">=", 3),
    ]


def to_markdown(summary: dict) -> str:
    """``bench.md``: the bench summary as Markdown tables, figures beside their targets."""
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
    stsf = _row(summary, "e:")
    ekf = _row(summary, "f:")
    frame = stsf["ms_per_frame"]
    latency_rows = [
        {
            "stage": f"camera frame ({stsf['renderer']}: render, lens, sensor)",
            "ms per frame": frame.get("camera frame"),
            "paper ms": None,
        },
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
    fast = [_row(summary, case) for case in ("h:", "i:", "j:")]
    reference_rows = [
        {
            "case": r["case"],
            "update, ms per camera frame": next(
                v for k, v in r["ms_per_frame"].items() if k.endswith(" update")
            ),
            "every stage, ms per step": r["estimator_ms_per_step"],
        }
        for r in fast
    ]
    parts = [
        f"# stsf-gym bench\n\n{m['cpu']}, {m['cores']} cores, Python {m['python']}; "
        "each speed case in its own process pinned to one core. Reference workload "
        f"(fixed Python + numpy work, best of 3): {m['reference_ms']:.1f} ms.\n",
        "## Env speed (IRL corridor, follower driving)\n\n" + markdown_table(speed_rows),
        "## Renderers alone (one core)\n\n" + markdown_table(summary["render"]),
        "## Latency per camera frame (320x240)\n\n" + markdown_table(latency_rows),
        "## The references beside the EKF (fast sensor mode, one core)\n\n"
        + markdown_table(reference_rows),
    ]
    if "detector_vs_aruco" in stsf:
        a = stsf["detector_vs_aruco"]
        parts.append(
            f"Detector {a['detector_ms']:.3f} ms vs ArUco detectMarkers {a['aruco_ms']:.3f} ms "
            f"per frame on the same {a['frames']} frames: ratio {a['ratio']:.2f}.\n"
        )
    v = summary["vector"]
    parts.append(
        "## AsyncVectorEnv (rendered STSF pipeline)\n\n"
        f"1 worker {v['steps_per_s_1_worker']:.0f} steps/s, 2 workers "
        f"{v['steps_per_s_2_workers']:.0f} steps/s: {v['speed_up']:.2f}x.\n"
    )
    if "profile" in stsf:
        rows = [{**p, "own_share": f"{100 * p['own_share']:.1f} %"} for p in stsf["profile"]]
        parts.append(f"## Where the time goes ({PROFILED_CASE})\n\n" + markdown_table(rows))
    if "recording" in summary:
        parts.append(
            "## Recording (IRL corridor, follower on STSF; overhead: the recorder's CPU time "
            "over the unrecorded episode's)\n\n"
            + markdown_table(summary["recording"]["recordings"])
            + "\nReplay of the lossless MCAP (reading and decoding included; speed-up in CPU "
            "time):\n\n"
            + markdown_table(summary["recording"]["replays"])
            + "\nImport of the writers' libraries (once per process, CPU s): "
            + ", ".join(f"{k} {v:.2f}" for k, v in summary["recording"]["import_cpu_s"].items())
            + "\n"
        )
    parts.append("## Targets\n\n" + markdown_table(summary["targets"]))
    return "\n".join(parts)
