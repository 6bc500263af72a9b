"""Env steps per second on a suite world: the cost of one 0.1 s step as learners and
benchmarks pay it.

Four cases, each on ``stsf_gym/Suite-Corridor-*`` (generated test worlds, the declared-arrival
task): the true pose with the camera off, and STSF on the suite's fast camera, each driven by
the follower and by random actions (a seeded generator). A case steps ``steps`` times,
resetting at each episode's end, after ``warmup`` steps that are not timed.

This file is also a script (``python step.py --json``) that needs nothing but Gymnasium and
``stsf_gym``'s public names (its env ids and :func:`~stsf_gym.agents.registry.make_agent`), so
:func:`side_by_side` runs the same cases on another checkout or installed version, in the same
run, for ratios that other jobs on the machine disturb alike. Run on this code, it also reports
the package modules it loaded (``--modules``), for the bench's provenance.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import pstats
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

#: The suite's task as the ids had it before they carried the STOP entry (and as a baseline
#: checkout's ids may still have it): random actions would declare arrival at every other step
NO_STOP = {"task": {"stop_action": False}}
#: case -> (env id, env overrides, driver)
CASES: dict[str, tuple[str, dict, str]] = {
    "truth, camera off, follower": (
        "stsf_gym/Suite-Corridor-Truth-v0",
        {"camera": {"enabled": False}, **NO_STOP},
        "follower",
    ),
    "truth, camera off, random": (
        "stsf_gym/Suite-Corridor-Truth-v0",
        {"camera": {"enabled": False}, **NO_STOP},
        "random",
    ),
    "stsf, fast camera, follower": ("stsf_gym/Suite-Corridor-STSF-v0", NO_STOP, "follower"),
    "stsf, fast camera, random": ("stsf_gym/Suite-Corridor-STSF-v0", NO_STOP, "random"),
}
#: A step's stages, each the cumulative time of a function as both this code and a baseline
#: checkout (from commit a543992 on) name it (the files it may be in, function; its outermost
#: call where several match): the env's step and, within it, the physics, the sonar and the fast
#: camera; the pose wrapper's step (which holds the env's; in ``wrappers.py`` before the
#: wrappers became a package) and, within it, the estimator's camera frames and the rest of its
#: update; the camera pointing; the follower.
STAGES: dict[str, tuple[tuple[str, ...], str]] = {
    "env step": (("corridor_env.py",), "step"),
    "physics": (("simulator.py",), "step"),
    "sonar": (("sonar.py",), "read"),
    "fast camera": (("fast_camera.py",), "capture"),
    "pose wrapper": (("estimate.py", "wrappers.py"), "step"),
    "estimator, frames": (("landmark_fusion.py",), "_frame"),
    "estimator, update": (("landmark_fusion.py",), "update"),
    "camera pointing": (("camera_pointing.py",), "pan"),
    "follower": (("follower.py",), "act"),
}
#: The timed steps are split into segments of this many. A segment is the same steps in every
#: round (a seed fixes them), so each side's fastest time of each segment over the rounds,
#: summed, is its cost with the least interference: a shared machine's load comes and goes
#: within a run, and seldom slows one segment in every round.
SEGMENT_STEPS = 100
BASELINE_PROBE_S = 120  # s: a baseline interpreter importing stsf_gym (numba, torch) cold


def measure(
    case: str,
    steps: int = 1500,
    warmup: int = 100,
    seed: int = 0,
    profiler: cProfile.Profile | None = None,
) -> dict:
    """Steps per second of wall time and of the process's CPU time for ``case``, and the wall
    seconds of each :data:`SEGMENT_STEPS` steps; ``profiler`` watches the timed steps (not the
    warm-up: imports, compiled loops' loading) if given."""
    import stsf_gym  # noqa: F401 - registers the ids
    from stsf_gym.agents.registry import make_agent

    env_id, overrides, driver = CASES[case]
    env = gym.make(env_id, **overrides)
    follower = make_agent("follower") if driver == "follower" else None
    rng = np.random.default_rng(seed)
    episodes = [seed]

    def start():
        obs, _ = env.reset(seed=episodes[-1])
        episodes.append(episodes[-1] + 1)
        if follower is not None:
            follower.begin(env)
        return obs

    def drive(count: int, obs):
        for _ in range(count):
            if follower is None:
                action = rng.uniform(env.action_space.low, env.action_space.high)
            else:
                action = follower.act(obs)
            obs, _, terminated, truncated, _ = env.step(action.astype(np.float32))
            if terminated or truncated:
                obs = start()
        return obs

    obs = drive(warmup, start())
    if profiler is not None:
        profiler.enable()
    segments = []
    cpu = time.process_time()
    for done in range(0, steps, SEGMENT_STEPS):
        start_s = time.perf_counter()
        obs = drive(min(SEGMENT_STEPS, steps - done), obs)
        segments.append(time.perf_counter() - start_s)
    cpu = time.process_time() - cpu
    if profiler is not None:
        profiler.disable()
    env.close()
    return {
        "case": case,
        "steps": steps,
        "episodes": len(episodes) - 1,
        "steps_per_s": steps / sum(segments),
        "steps_per_cpu_s": steps / cpu,
        "segment_s": segments,
    }


def profile(case: str, steps: int = 1500, seed: int = 0, count: int = 25) -> list[dict]:
    """cProfile's ``count`` functions with the most own time while ``case`` runs."""
    profiler = cProfile.Profile()
    row = measure(case, steps, seed=seed, profiler=profiler)
    total = row["steps"] / row["steps_per_s"]
    stats = pstats.Stats(profiler).stats
    top = sorted(stats.items(), key=lambda item: item[1][2], reverse=True)[:count]
    return [
        {
            "function": f"{Path(file).name}:{line} {name}",
            "own_share": own / total,
            "calls": calls,
            "cumulative_s": cumulative,
        }
        for (file, line, name), (_, calls, own, cumulative, _) in top
    ]


def stage_profile(case: str, steps: int = 1500, seed: int = 0) -> dict:
    """Milliseconds per step of each of :data:`STAGES` while cProfile watches ``case`` (its
    overhead inflates every figure; compare shares, or the same stage of two codes), and
    the whole step's."""
    profiler = cProfile.Profile()
    row = measure(case, steps, seed=seed, profiler=profiler)
    cumulative: dict[tuple[str, str], float] = {}
    for (file, _, name), (*_, seconds, _) in pstats.Stats(profiler).stats.items():
        key = (Path(file).name, name)
        cumulative[key] = max(cumulative.get(key, 0.0), seconds)
    return {
        "case": case,
        "step_ms": 1e3 / row["steps_per_s"],
        "stages_ms": {
            stage: 1e3 * max(cumulative.get((file, name), 0.0) for file in files) / steps
            for stage, (files, name) in STAGES.items()
        },
    }


def step_section(
    steps: int = 1500, seed: int = 0, baseline: Path | None = None, rounds: int = 5
) -> dict:
    """The bench's ``step`` section: each case's steps/s, of wall time and of the process's CPU
    time, each the best of ``rounds`` fresh processes, and (``*_segments``) from each segment's
    fastest time over the rounds (:data:`SEGMENT_STEPS`), on this code and, with ``baseline``
    (a checkout's folder, or a Python interpreter with another ``stsf_gym`` installed), on that
    code too; their ratios, this code over the baseline, and each round's ratio of the two runs
    made back to back (``ratio_rounds``: mean, std, count, values). The two sides alternate case
    by case, the first of a pair switching every round, so that a change of load (a virtual
    machine's neighbours) hits both alike."""
    from stsf_gym.results.machine_speed import reference_ms

    sides = {"this": [sys.executable]}
    rows = {case: {"case": case} for case in CASES}
    fastest: dict[tuple[str, str], np.ndarray] = {}  # (case, side) -> each segment's fastest
    paired: dict[str, list[float]] = {case: [] for case in CASES}  # each round's ratio
    with tempfile.TemporaryDirectory() as staged:
        if baseline is not None:
            sides["baseline"] = _interpreter(Path(baseline), Path(staged))
        for round_ in range(rounds):
            for case in CASES:
                rates = {}
                for label in sorted(sides, reverse=bool(round_ % 2)):
                    arguments = ["--case", case, "--steps", str(steps), "--seed", str(seed)]
                    (run,) = _run_script(sides[label], arguments, label == "this")
                    best, rates[label] = rows[case], run["steps_per_s"]
                    best[label] = max(best.get(label, 0.0), run["steps_per_s"])
                    cpu = f"{label}_cpu"
                    best[cpu] = max(best.get(cpu, 0.0), run["steps_per_cpu_s"])
                    segments = np.array(run["segment_s"])
                    known = fastest.setdefault((case, label), segments)
                    fastest[case, label] = np.minimum(known, segments)
                if baseline is not None:
                    paired[case].append(rates["this"] / rates["baseline"])
        profiles = [
            {
                "side": label,
                **_run_script(
                    sides[label],
                    ["--stages", case, "--steps", str(steps), "--seed", str(seed)],
                    label == "this",
                ),
            }
            for case in CASES
            if case.endswith("follower")
            for label in sorted(sides)
        ]
    for (case, label), segments in fastest.items():
        rows[case][f"{label}_segments"] = steps / float(segments.sum())
    if baseline is not None:
        from stsf_gym.results.schema import stat

        for case, row in rows.items():
            row["ratio"] = row["this"] / row["baseline"]
            row["ratio_cpu"] = row["this_cpu"] / row["baseline_cpu"]
            row["ratio_segments"] = row["this_segments"] / row["baseline_segments"]
            row["ratio_rounds"] = stat(paired[case])
    return {
        "steps": steps,
        "rounds": rounds,
        "baseline": None if baseline is None else str(baseline),
        "reference_ms": reference_ms(),
        "rows": list(rows.values()),
        "profiles": profiles,
    }


#: What the baseline interpreter's probe prints once it has imported ``stsf_gym``.
PROBE_REPLY = "stsf_gym imported"


def check_baseline(baseline: Path) -> None:
    """Refuse a ``--baseline`` that is neither a Python interpreter that imports ``stsf_gym``
    nor a checkout (``stsf_gym/`` and the folders
    :data:`~stsf_gym.layers.MAPPED_FOLDERS`), naming what it lacks, before any case runs.
    """
    # this process's own helpers: the file also runs as a script on a baseline's package
    from stsf_gym.layers import MAPPED_FOLDERS
    from stsf_gym.validation import ConfigError

    if baseline.is_file() and os.access(baseline, os.X_OK):
        probe = [str(baseline), "-c", f"import stsf_gym; print({PROBE_REPLY!r})"]
        try:
            imported = subprocess.run(
                probe, capture_output=True, text=True, timeout=BASELINE_PROBE_S
            )
        except (OSError, subprocess.TimeoutExpired) as err:
            raise ConfigError(f"--baseline {baseline}: cannot run it as Python ({err})") from None
        if imported.returncode != 0 or imported.stdout.strip() != PROBE_REPLY:
            said = repr(imported.stdout.strip()[:60]) if imported.stdout.strip() else "nothing"
            raise ConfigError(  # /bin/true exits 0 and says nothing
                f"--baseline {baseline}: not a Python interpreter with stsf-gym installed "
                f"(`{baseline} -c 'import stsf_gym; print(...)'` exited "
                f"{imported.returncode} and printed {said})"
            )
        return
    missing = [
        name for name in ("stsf_gym/__init__.py", *MAPPED_FOLDERS) if not (baseline / name).exists()
    ]
    if missing:
        raise ConfigError(
            f"--baseline {baseline}: neither a Python interpreter nor a checkout of stsf-gym "
            f"(it lacks {', '.join(missing)})"
        )


def _interpreter(baseline: Path, staged: Path) -> list[str]:
    """The command that runs Python on the baseline's code: the interpreter itself, or this one
    with the checkout's folders laid out as installed (``stsf_gym`` with ``envs``, ``agents``
    and ``configs`` inside it) first on ``sys.path``."""
    from stsf_gym.layers import MAPPED_FOLDERS

    check_baseline(baseline)
    if baseline.is_file():
        return [str(baseline)]
    package = staged / "stsf_gym"
    package.mkdir()
    for entry in (baseline / "stsf_gym").iterdir():
        (package / entry.name).symlink_to(entry.resolve())
    for folder in MAPPED_FOLDERS:
        (package / folder).symlink_to((baseline / folder).resolve())
    return [
        sys.executable,
        "-c",
        f"import sys; sys.path.insert(0, {str(staged)!r}); "
        "sys.argv = sys.argv[1:]; exec(open(sys.argv[0]).read())",
    ]


def _run_script(command: list[str], arguments: list[str], this_code: bool) -> list | dict:
    """This file run as a script by ``command`` with ``arguments``: its output; on
    ``this_code`` (this package, not a baseline) the package modules it loaded are counted as
    the run's code."""
    modules = ["--modules"] if this_code else []
    done = subprocess.run(
        [*command, __file__, *arguments, *modules],
        capture_output=True,
        text=True,
        check=False,
        cwd=tempfile.gettempdir(),  # never the checkout's folder: its stsf_gym would shadow
    )
    if done.returncode:
        raise RuntimeError(f"{' '.join(command)} {__file__}: {done.stderr.strip()[-2000:]}")
    output = json.loads(done.stdout)
    if not this_code:
        return output
    from stsf_gym.results.code_identity import note_worker_modules

    note_worker_modules(output["modules"])
    return output["rows"]


def main() -> None:
    """``python step.py [--case C ...] [--steps N] [--seed S] [--modules]``: the rows of the
    cases (default all) as JSON on stdout (with ``--modules``, ``{"rows", "modules"}``: the
    package modules loaded, too); ``--profile C`` or ``--stages C`` profile case C instead."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1500)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--case", choices=list(CASES), action="append")
    parser.add_argument("--profile", choices=list(CASES))
    parser.add_argument("--stages", choices=list(CASES), help="ms per step of each stage")
    parser.add_argument("--modules", action="store_true", help="report the modules loaded, too")
    args = parser.parse_args()
    if args.profile:
        result = profile(args.profile, args.steps, args.seed)
    elif args.stages:
        result = stage_profile(args.stages, args.steps, args.seed)
    else:
        result = [measure(case, args.steps, seed=args.seed) for case in args.case or CASES]
    if args.modules:  # this code's own helper: a baseline's package may lack it
        from stsf_gym.results.code_identity import loaded_modules

        result = {"rows": result, "modules": loaded_modules()}
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
