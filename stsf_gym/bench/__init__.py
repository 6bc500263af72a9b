"""``stsf-gym bench``: the speed figures, each beside its target, in one run.

1. Env speed as a multiple of real time on one core (cases a-j of :mod:`.speed`), in wall and
   in CPU time, each as a ratio to the camera-off case of the run and as simulated seconds per
   reference workload, with the renderer named and the peak memory of each env process.
2. Each renderer alone (GL, PyBullet's EGL, TinyRenderer): ms per frame at 320x240 and
   640x480 on one core, and the GL camera's whole frame (render, lens, defocus, sensor).
3. Latency per camera frame of each stage (camera frame: render, lens and sensor; detection,
   motion stereo + STSF update, EKF update) beside the paper's 0.127 s to detect and 0.332 s
   to localise; the detector and STSF's whole detection stage beside OpenCV's ArUco
   ``detectMarkers`` on the same frames.
4. ``AsyncVectorEnv`` and ``SubprocVecEnv`` throughput of the rendered and the fast-mode STSF
   pipelines with 1 and 2 workers.
5. Where the time goes: cProfile's top functions over the camera pipeline (case e).
6. Recording (:mod:`.recording`): what ``--record`` adds to an episode's wall time, the files'
   sizes, and how much faster a replay of a recorded episode runs than the episode itself.
7. What a process costs (:mod:`.process_cost`): the env's and the training stack's import
   times and the first step (compiled kernels loaded from their cache included).

Writes ``bench.json`` and ``bench.md`` (ending in the targets table: each target measured, met
or the measured reason, and the load average at the run's start and end) to the output folder.
"""

from __future__ import annotations

import os
import platform
from pathlib import Path

from tqdm import tqdm

from stsf_gym.bench.process_cost import process_costs
from stsf_gym.bench.recording import recording_costs
from stsf_gym.bench.speed import CASES, FAST_CASES, render_latency, run_case, vector_scaling
from stsf_gym.bench.step import SEGMENT_STEPS, STAGES, step_section
from stsf_gym.io import markdown_table, write_atomic, write_json
from stsf_gym.recording import missing_modules
from stsf_gym.results.provenance import provenance, reference_ms

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


def run_step_bench(
    out: Path, steps: int = 1500, seed: int = 0, baseline: Path | None = None, rounds: int = 5
) -> dict:
    """The ``step`` section alone (:mod:`stsf_gym.bench.step`); writes bench.json / bench.md."""
    load_start = os.getloadavg()
    step = step_section(steps, seed, baseline, rounds)
    summary = {
        "machine": {**machine(), "load_average": [load_start, os.getloadavg()]},
        "step": step,
        "provenance": provenance({"steps": steps, "baseline": step["baseline"]}, timed=True),
    }
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "bench.json", summary)
    write_atomic(out / "bench.md", to_markdown(summary))
    return summary


def run_bench(
    out: Path,
    sim_seconds: float = 60.0,
    vector_steps: int = 1000,
    seed: int = 0,
    baseline: Path | None = None,
    rounds: int = 5,
):
    """Run every measurement; write bench.json / bench.md; return the summary."""
    load_start = os.getloadavg()
    step = step_section(seed=seed, baseline=baseline, rounds=rounds)
    speed = []
    for name in tqdm(CASES, desc="bench cases", unit="case"):
        fast_case = name.startswith(FAST_CASES)
        seconds = sim_seconds * (4 if fast_case else 1)  # fast cases: a longer, steadier span
        speed.append(run_case(name, seconds, seed, profile=name == PROFILED_CASE))
    renders = render_latency()
    vector = vector_scaling(vector_steps, seed)
    about = machine()
    summary = {
        "machine": {**about, "load_average": [load_start, os.getloadavg()]},
        "step": step,
        "speed": speed,
        "render": renders,
        "vector": vector,
        "process": process_costs(about["reference_ms"]),
    }
    if not missing_modules():  # the record extra: a core install measures no recording
        summary["recording"] = recording_costs(seed)
    summary["targets"] = targets(summary)
    summary["provenance"] = provenance(
        {"sim_seconds": sim_seconds, "vector_steps": vector_steps, "baseline": step["baseline"]},
        timed=True,
    )
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "bench.json", summary)
    write_atomic(out / "bench.md", to_markdown(summary))
    return summary


def _row(summary: dict, prefix: str) -> dict:
    return next(r for r in summary["speed"] if r["case"].startswith(prefix))


def add_ratios(summary: dict) -> None:
    """Each speed row's ratio to the camera-off case (``vs_camera_off``) and to the reference
    workload (``sim_s_per_reference``: simulated seconds run in the reference workload's
    time), so runs on different or busy machines compare; both from CPU time (the cost on one
    core; wall time on a shared machine also holds the other jobs' share)."""
    off = _row(summary, "a:")["x_real_time_cpu"]
    reference_s = summary["machine"]["reference_ms"] / 1e3
    for row in summary["speed"]:
        row["vs_camera_off"] = row["x_real_time_cpu"] / off
        row["sim_s_per_reference"] = row["x_real_time_cpu"] * reference_s


def targets(summary: dict) -> list[dict]:
    """Each speed target with what was measured and whether it holds (and, when it does not,
    what the measurement says holds it back)."""
    add_ratios(summary)
    stsf = _row(summary, "e:")
    ekf = _row(summary, "f:")
    fast_ekf, smoother, mcl = (_row(summary, case) for case in ("h:", "i:", "j:"))
    aruco = stsf.get("detector_vs_aruco", {})
    gl = next((r for r in summary["render"] if r["renderer"] == "gl"), {})
    nan = float("nan")
    gl_cases = [r["peak_rss_mb"] for r in summary["speed"] if r["renderer"] == "gl"]
    frame = stsf["ms_per_frame"]
    stages = ", ".join(f"{k} {v:.2f} ms" for k, v in frame.items())
    render_320 = gl.get("ms_320x240", nan)
    frame_640 = gl.get("camera_frame_ms_640x480", nan)
    checks = [
        (
            "e: camera + detector + STSF / camera off",
            stsf["vs_camera_off"],
            ">=",
            0.30,
            f"per camera frame: {stages}",
        ),
        (
            "f: camera + detector + EKF / camera off",
            ekf["vs_camera_off"],
            ">=",
            0.30,
            "as e, the EKF update in place of STSF's",
        ),
        (
            "camera frame 320x240 (render, lens, defocus, blur, sensor), ms",
            frame.get("camera frame", nan),
            "<=",
            1.5,
            f"{stsf.get('renders_per_frame') or nan:.2f} renders a frame (motion blur while "
            f"the camera pans) at {render_320:.2f} ms each; a still frame (one render) takes "
            f"{gl.get('camera_frame_ms_320x240', nan):.2f} ms",
        ),
        (
            "camera frame 640x480 / plain GL render 640x480",
            frame_640 / gl.get("ms_640x480", nan),
            "<=",
            2.0,
            "lens remap, defocus and sensor on the CPU",
        ),
        (
            "detection with track-aided matching / ArUco detectMarkers, same frames",
            aruco.get("pipeline_ratio", nan),
            "<=",
            1.0,
            f"{aruco.get('pipeline_ms', nan):.2f} ms against ArUco's "
            f"{aruco.get('aruco_ms', nan):.2f} ms; the plain detector alone "
            f"{aruco.get('detector_ms', nan):.2f} ms",
        ),
        (
            "g: fast sensor mode + STSF / camera off",
            _row(summary, "g:")["vs_camera_off"],
            ">=",
            0.6,
            f"the STSF estimator takes {_row(summary, 'g:')['estimator_ms_per_step']:.2f} ms "
            f"(wall) per step against {1e3 / _row(summary, 'a:')['steps_per_s']:.2f} ms for a "
            "whole camera-off step",
        ),
        (
            "peak memory per GL-camera env process, MB",
            max(gl_cases, default=nan),
            "<=",
            250,
            "PyBullet, OpenCV and Mesa's llvmpipe loaded in every process",
        ),
    ]
    load = summary["machine"].get("load_average")
    busy = f"; 1-min load average {load[0][0]:.1f} -> {load[1][0]:.1f}" if load else ""
    for v in summary["vector"]:
        wall, worker, parent = (
            v[f"{key}_2_workers"]
            for key in ("wall_ms_per_step", "worker_cpu_ms_per_step", "parent_cpu_ms_per_step")
        )
        alone_cpu = v.get("worker_cpu_ms_per_step_1_worker", nan)
        alone_wall = v.get("wall_ms_per_step_1_worker", nan)
        cores = alone_cpu / alone_wall
        threads = ": OpenCV's and llvmpipe's threads" if cores > 1.05 else ""
        checks.append(
            (
                f"2 workers / 1 worker, {v['vector env']}, {v['pipeline']}",
                v["speed_up"],
                ">=",
                1.8,
                f"one worker alone: {alone_cpu:.2f} ms CPU per step in {alone_wall:.2f} ms wall "
                f"({cores:.2f} cores{threads}); a "
                f"2-worker step: {wall:.2f} ms wall = a worker's {worker:.2f} ms CPU + the "
                f"parent's {parent:.2f} ms + {wall - worker - parent:.2f} ms waiting (for the "
                f"slower worker, or for a core){busy}",
            )
        )
    checks += [
        ("GL render 320x240, ms per frame", render_320, "<=", 2.0, ""),
        ("GL render 640x480, ms per frame", gl.get("ms_640x480", nan), "<=", 4.0, ""),
        ("STSF update, ms per frame", frame["stsf update"], "<", 0.5, ""),
        ("detector / ArUco time (plain detector)", aruco.get("ratio", nan), "<=", 2.0, ""),
        (
            "smoother update, ms per camera frame",
            smoother["ms_per_frame"]["smoother update"],
            "<=",
            2.0,
            "",
        ),
        ("MCL, ms per step (every stage)", mcl["estimator_ms_per_step"], "<=", 3.0, ""),
    ]
    if "recording" in summary:
        checks += [(*check, "") for check in recording_checks(summary["recording"])]
    checks += process_checks(summary["process"])
    rows = []
    for name, value, op, bound, reason in checks:
        met = bool({">=": value >= bound, "<=": value <= bound, "<": value < bound}[op])
        rows.append(
            {
                "target": name,
                "measured": value,
                "bound": f"{op} {bound:g}",
                "met": met,
                "reason": "" if met else reason,
            }
        )
    rows.append(
        {
            "target": "EKF update, ms per frame (no target)",
            "measured": ekf["ms_per_frame"]["ekf update"],
            "bound": "-",
            "met": True,
            "reason": f"EKF every stage {fast_ekf['estimator_ms_per_step']:.3f} ms per step",
        }
    )
    return rows


def process_checks(process: dict) -> list[tuple[str, float, str, float, str]]:
    """The process-cost targets, in reference workloads (about 50 ms each on this project's
    2-core machine): the env's import within a second, the training stack's within 3 s (torch
    and SB3 are most of it), the first step within 5 s (numba's own start-up about 3 s)."""
    return [
        ("import stsf_gym, reference workloads", process["import_env_references"], "<=", 20, ""),
        (
            "import the training stack, reference workloads",
            process["import_training_references"],
            "<=",
            60,
            "torch and stable-baselines3 imported by the trainer's modules",
        ),
        (
            "first step of STSF (make, reset, step), reference workloads",
            process["first_step_references"],
            "<=",
            100,
            "numba's start-up when the first compiled kernel loads from its cache",
        ),
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


def _load_text(m: dict) -> str:
    """The load averages (1, 5, 15 min) at the run's start and end: the machine is shared."""
    if "load_average" not in m:
        return ""
    start, end = (" / ".join(f"{x:.2f}" for x in load) for load in m["load_average"])
    return f"Load average (1 / 5 / 15 min) at the start {start}, at the end {end}."


def step_markdown(step: dict) -> str:
    """The ``step`` section as Markdown: steps/s per case, beside the baseline's if run."""
    against = f" against {step['baseline']}, alternating" if step["baseline"] else ""
    rows = [{k: v for k, v in row.items() if k != "ratio_rounds"} for row in step["rows"]]
    for row, measured in zip(rows, step["rows"], strict=True):
        if "ratio_rounds" in measured:
            values = measured["ratio_rounds"]["values"]
            row["ratio, rounds (lowest-highest)"] = f"{min(values):.2f}-{max(values):.2f}"
    return (
        f"## Env steps per second (suite corridor world, {step['steps']} steps a case, best "
        f"of {step['rounds']} fresh processes a case{against}; of wall time and, `_cpu`, of "
        f"the process's CPU time; `_segments`: each {SEGMENT_STEPS} steps' fastest time over "
        f"the rounds, summed; each round's ratio of its two runs)\n\nReference workload "
        f"{step['reference_ms']:.1f} ms.\n\n" + markdown_table(rows) + _profiles_markdown(step)
    )


def _profiles_markdown(step: dict) -> str:
    """Each profiled case's stages, ms per step under cProfile, one column per code."""
    cases: dict[str, dict[str, dict]] = {}
    for profile in step.get("profiles", []):
        cases.setdefault(profile["case"], {})[profile["side"]] = profile
    text = ""
    for case, sides in cases.items():
        rows = [
            {"stage": stage, **{side: p["stages_ms"][stage] for side, p in sides.items()}}
            for stage in STAGES
            if any(p["stages_ms"][stage] for p in sides.values())  # none: not in this case
        ]
        rows.append({"stage": "whole step", **{side: p["step_ms"] for side, p in sides.items()}})
        text += (
            f"\n### Where a step goes: {case} (ms per step under cProfile, one profiled process "
            "per code; nested stages: physics, sonar and fast camera are within the env step, "
            "which is within the pose wrapper's step, as are the estimator and the camera "
            "pointing; the estimator's update holds its frames)\n\n" + markdown_table(rows)
        )
    return text


def to_markdown(summary: dict) -> str:
    """``bench.md``: the bench summary as Markdown tables, figures beside their targets."""
    m = summary["machine"]
    if "speed" not in summary:  # the step section alone
        return (
            f"# stsf-gym bench: step\n\n{m['cpu']}, {m['cores']} cores, Python {m['python']}. "
            + _load_text(m)
            + "\n\n"
            + step_markdown(summary["step"])
        )
    speed_rows = [
        {
            "case": r["case"],
            "renderer": r["renderer"],
            "x real time": r["x_real_time"],
            "x real time, CPU": r["x_real_time_cpu"],
            "/ camera off (CPU)": r["vs_camera_off"],
            "sim s per reference": r["sim_s_per_reference"],
            "steps/s": r["steps_per_s"],
            "peak MB": r["peak_rss_mb"],
        }
        for r in summary["speed"]
    ]
    render_rows = [
        {**r, **{f"{k} / reference": r[k] / m["reference_ms"] for k in r if k.endswith("0")}}
        for r in summary["render"]
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
        f"(fixed Python + numpy work, best of 3): {m['reference_ms']:.1f} ms. "
        + _load_text(m)
        + "\n",
        step_markdown(summary["step"]) if "step" in summary else "",
        "## Env speed (IRL corridor, follower driving)\n\nEach speed also as a ratio to the "
        "camera-off case of this run and as simulated seconds per reference workload, both from "
        "the process's CPU time (x real time, CPU: simulated s per CPU s; the wall-time figure "
        "beside it also holds what other jobs took from the core).\n\n"
        + markdown_table(speed_rows),
        "## Renderers alone (one core; GL also the whole camera frame of a still camera)\n\n"
        + markdown_table(render_rows),
        "## Latency per camera frame (320x240)\n\n" + markdown_table(latency_rows),
        "## The references beside the EKF (fast sensor mode, one core)\n\n"
        + markdown_table(reference_rows),
    ]
    if "detector_vs_aruco" in stsf:
        a = stsf["detector_vs_aruco"]
        parts.append(
            f"Detector {a['detector_ms']:.3f} ms, STSF's whole detection stage (track-aided "
            f"matching, undistortion) {a['pipeline_ms']:.3f} ms, ArUco detectMarkers "
            f"{a['aruco_ms']:.3f} ms per frame on the same {a['frames']} frames: ratios "
            f"{a['ratio']:.2f} and {a['pipeline_ratio']:.2f}.\n"
        )
    parts.append(
        "## Vector envs, 1 and 2 workers (steps/s of all workers together)\n\n"
        + markdown_table(summary["vector"])
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
    if "process" in summary:
        c = summary["process"]
        parts.append(
            "## What a process costs (fresh processes, best of 3)\n\n"
            f"Import of `stsf_gym` {c['import_env_s']:.2f} s, of the training stack "
            f"{c['import_training_s']:.2f} s more, the first step of STSF (make, reset, step) "
            f"{c['first_step_s']:.2f} s; peak memory of each env case in the speed table.\n"
        )
    parts.append("## Targets\n\n" + markdown_table(summary["targets"]))
    return "\n".join(parts)
