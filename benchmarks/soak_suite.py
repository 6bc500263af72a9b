"""Soak of the benchmark's hardest suite: every pose source, faults on, parallel workers.

    python benchmarks/soak_suite.py --suite sparse --minutes 60 --workers 2 [--rerun 10] [--json]

The benchmark's episodes (the follower on every pose source, seed by seed, on the suite's test
worlds) with the fault set ``configs/faults/soak.yaml`` run in ``--workers`` forkserver
processes until ``--minutes`` have passed (episodes under way then finish). Each worker reports
its resident memory after every episode. Then the first ``--rerun`` finished episodes run again
in this process and must give identical results. Exits with status 1 on an episode that
raised, a rerun that differs, or a worker whose memory grew by more than
:data:`MAX_RSS_GROWTH_MB` from its warm state (after as many episodes as there are pose
sources: each one's libraries imported, gtsam's among them) to its last episode.
"""

from __future__ import annotations

import argparse
import itertools
import json
import multiprocessing
import os
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

from tqdm import tqdm

from stsf_gym.config_files import CONFIG_DIR
from stsf_gym.envs.suite import load_suite
from stsf_gym.estimators import ESTIMATORS
from stsf_gym.experiments.benchmark.run import benchmark_cells
from stsf_gym.experiments.fault_runs import load_fault_set
from stsf_gym.experiments.jobs.cells import run_cell

FAULTS = CONFIG_DIR / "faults" / "soak.yaml"
MAX_RSS_GROWTH_MB = 50.0  # an episode's arrays are a few MB; a leak per episode adds up


def rss_mb() -> float:
    """This process's resident memory now (MB)."""
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6


def measured_episode(cell: dict) -> tuple[dict, int, float]:
    """One cell's result, the worker's pid and its memory after the episode."""
    return run_cell(cell), os.getpid(), rss_mb()


def soak_cells(suite: str):
    """The benchmark's cells with the soak's faults, seed after seed, without end."""
    loaded = load_suite(suite)
    # the soak's faults name no board: checked once, on the default world, in the suite's env
    faults = load_fault_set(FAULTS, "irl_corridor", loaded.env)[1]
    for seed in itertools.count():
        for cell in benchmark_cells(loaded, ["follower"], list(ESTIMATORS), [seed]):
            yield {**cell, "env": {**cell["env"], "faults": faults}}


def soak(suite: str, minutes: float, workers: int, rerun: int) -> dict:
    started, deadline = time.monotonic(), time.monotonic() + 60 * minutes
    cells, done, memory = soak_cells(suite), [], {}
    context = multiprocessing.get_context("forkserver")
    bar = tqdm(desc=f"soak {suite}", unit="episode")
    with ProcessPoolExecutor(workers, mp_context=context) as pool:
        running = {pool.submit(measured_episode, c): c for c in itertools.islice(cells, workers)}
        while running:
            finished, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in finished:
                cell = running.pop(future)
                result, pid, rss = future.result()
                done.append((cell, result))
                memory.setdefault(pid, []).append(rss)
                bar.update()
                if time.monotonic() < deadline:
                    following = next(cells)
                    running[pool.submit(measured_episode, following)] = following
    bar.close()
    errors = [(c["estimator"], c["seed"], r["error"]) for c, r in done if "error" in r]
    reruns = [run_cell(cell) == result for cell, result in done[:rerun]]
    return {
        "suite": suite,
        "minutes": (time.monotonic() - started) / 60,
        "workers": workers,
        "episodes": len(done),
        "episodes_per_pose_source": {
            e: sum(c["estimator"] == e for c, _ in done) for e in ESTIMATORS
        },
        "errors": errors,
        "rss_mb": {
            str(pid): {
                "first": v[0],
                "warm": v[min(len(ESTIMATORS), len(v)) - 1],
                "last": v[-1],
                "max": max(v),
                "episodes": len(v),
                "values": v,
            }
            for pid, v in memory.items()
        },
        "reruns": len(reruns),
        "reruns_identical": sum(reruns),
    }


def failures(report: dict) -> list[str]:
    problems = [f"{e} seed {s}: {err}" for e, s, err in report["errors"]]
    if report["reruns_identical"] != report["reruns"]:
        problems.append(f"{report['reruns'] - report['reruns_identical']} reruns differ")
    for pid, rss in report["rss_mb"].items():
        if rss["last"] - rss["warm"] > MAX_RSS_GROWTH_MB:
            problems.append(f"worker {pid} grew {rss['last'] - rss['warm']:.0f} MB")
    return problems


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="sparse")
    parser.add_argument("--minutes", type=float, default=60.0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rerun", type=int, default=10, help="episodes run again (10)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    report = soak(args.suite, args.minutes, args.workers, args.rerun)
    problems = failures(report)
    if args.json:
        print(json.dumps({**report, "failures": problems}, indent=2))
    else:
        print(
            f"{report['episodes']} episodes of suite {args.suite} in {report['minutes']:.1f} min "
            f"with {args.workers} workers; {len(report['errors'])} raised; reruns identical "
            f"{report['reruns_identical']}/{report['reruns']}"
        )
        for pid, rss in report["rss_mb"].items():
            print(
                f"worker {pid}: {rss['episodes']} episodes, RSS {rss['first']:.0f} MB after the "
                f"first, {rss['warm']:.0f} MB once every pose source ran, {rss['last']:.0f} MB "
                f"after the last (max {rss['max']:.0f})"
            )
    for problem in problems:
        print(f"FAILED: {problem}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
