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
from stsf_gym.bench.report import to_markdown
from stsf_gym.bench.speed import (
    CASES,
    FAST_CASES,
    PROFILED_CASE,
    render_latency,
    run_case,
    vector_scaling,
)
from stsf_gym.bench.step import step_section
from stsf_gym.bench.targets import targets
from stsf_gym.io import write_atomic, write_json
from stsf_gym.recording import missing_modules
from stsf_gym.results.machine_speed import reference_ms
from stsf_gym.results.provenance import provenance


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
