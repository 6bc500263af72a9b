"""``bench.md``: the summary of ``stsf-gym bench`` as Markdown, section by section, ending
in the targets table."""

from __future__ import annotations

from stsf_gym.bench.speed import PROFILED_CASE
from stsf_gym.bench.step import SEGMENT_STEPS, STAGES
from stsf_gym.bench.targets import speed_row
from stsf_gym.io import markdown_table

PAPER_MS = {"detect": 127.0, "localise": 332.0}  # sect. 4.3, 1 GHz Pentium IV


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
    stsf = speed_row(summary, "e:")
    ekf = speed_row(summary, "f:")
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
    fast = [speed_row(summary, case) for case in ("h:", "i:", "j:")]
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
