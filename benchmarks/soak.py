"""Soak test: many steps in parallel workers against a serial run, and many env lifetimes.

    python benchmarks/soak.py --steps 200000 --workers 2 [--cycles 1000] [--json]

``--steps``: camera-off corridor envs, one per worker, driven by seeded piecewise-constant
actions (forward-biased, turning at random, so episodes end on walls and auto-reset) in an
``AsyncVectorEnv`` (forkserver workers), then the same seeds and actions in a
``SyncVectorEnv`` in this process. Every observation, reward, episode end and true pose goes
into a SHA-256 per run; the two must match, and nothing may be NaN or infinite.

``--cycles``: make, reset, step and close one env that many times in this process; PyBullet
clients must be disconnected after ``close``, every client must hold the same number of
bodies, and the resident memory may grow by less than 20 MB after a warm-up.

Exits with status 1 when a check fails.
"""

from __future__ import annotations

import argparse
import functools
import gc
import hashlib
import json
import os
import sys
import time

import gymnasium as gym
import numpy as np
import pybullet

ENV_ID = "stsf_gym:stsf_gym/Corridor-v0"  # the module prefix registers the id in workers
ENV_KWARGS = {"camera__enabled": False}
SWITCH_PROB = 0.05  # chance per step that an env's action changes
MAX_RSS_GROWTH_MB = 20.0
WARMUP_CYCLES = 20


def seeded_actions(rng: np.random.Generator, current: np.ndarray) -> np.ndarray:
    """Next actions of all envs: each keeps its action or, now and then, draws a new one."""
    switch = rng.random(len(current)) < SWITCH_PROB
    fresh = np.column_stack(
        [rng.uniform(0.2, 1.0, len(current)), rng.uniform(-0.8, 0.8, len(current))]
    )
    return np.where(switch[:, None], fresh, current).astype(np.float32)


def drive(vec: gym.vector.VectorEnv, steps: int, seed: int) -> dict:
    """Run ``vec`` for ``steps`` vector steps; the trajectory's hash and its episode count."""
    digest = hashlib.sha256()
    rng = np.random.default_rng(seed)
    obs, infos = vec.reset(seed=[seed + i for i in range(vec.num_envs)])
    actions = np.tile(np.float32([0.5, 0.0]), (vec.num_envs, 1))
    episodes = 0
    for step in range(steps):
        actions = seeded_actions(rng, actions)
        obs, rewards, terminated, truncated, infos = vec.step(actions)
        arrays = [obs[k] for k in sorted(obs)] + [rewards, terminated, truncated]
        arrays.append(infos["true_pose"])
        for array in arrays:
            digest.update(np.ascontiguousarray(array).tobytes())
        for name, array in (("sonar", obs["sonar"]), ("reward", rewards), ("pose", arrays[-1])):
            if not np.all(np.isfinite(array)):
                raise FloatingPointError(f"non-finite {name} at vector step {step}: {array}")
        episodes += int(np.sum(terminated | truncated))
    return {"sha256": digest.hexdigest(), "episodes": episodes}


def soak(steps: int, workers: int, seed: int = 0, env_kwargs: dict | None = None) -> dict:
    """``steps`` env steps (over ``workers`` envs) in parallel, then serially; compared.

    ``env_kwargs`` replace the camera-off default (e.g. to hash rendered images too).
    """
    kwargs = ENV_KWARGS if env_kwargs is None else env_kwargs
    make = [functools.partial(gym.make, ENV_ID, **kwargs)] * workers
    vector_steps = -(-steps // workers)
    report: dict = {"steps": vector_steps * workers, "workers": workers, "seed": seed}
    for name, vec_cls, vec_kwargs in (
        ("parallel", gym.vector.AsyncVectorEnv, {"context": "forkserver"}),
        ("serial", gym.vector.SyncVectorEnv, {}),
    ):
        vec = vec_cls(make, **vec_kwargs)
        try:
            start = time.perf_counter()
            run = drive(vec, vector_steps, seed)
            elapsed = time.perf_counter() - start
            run["renderers"] = sorted(set(vec.get_attr("renderer")))
        finally:
            vec.close()
        report[name] = {**run, "seconds": elapsed, "steps_per_s": report["steps"] / elapsed}
    report["identical"] = report["parallel"]["sha256"] == report["serial"]["sha256"]
    return report


def rss_mb() -> float:
    """Resident memory of this process (MB), from /proc/self/statm."""
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 1e6


def cycle_envs(cycles: int, steps_per_cycle: int = 5, seed: int = 0) -> dict:
    """Make, reset, step and close an env ``cycles`` times; clients, bodies and memory."""
    clients, bodies, left_connected = set(), set(), 0
    baseline = None
    for cycle in range(cycles):
        if cycle == min(WARMUP_CYCLES, cycles // 2):
            gc.collect()
            baseline = rss_mb()
        env = gym.make(ENV_ID, **ENV_KWARGS)
        env.reset(seed=seed + cycle)
        for _ in range(steps_per_cycle):
            env.step(np.float32([0.5, 0.2]))
        client = env.unwrapped.sim.client
        clients.add(client._client)
        bodies.add(client.getNumBodies())
        env.close()
        left_connected += pybullet.getConnectionInfo(physicsClientId=client._client)["isConnected"]
    gc.collect()
    return {
        "cycles": cycles,
        "client_ids": sorted(clients),
        "bodies_per_client": sorted(bodies),
        "clients_left_connected": left_connected,
        "rss_growth_mb": rss_mb() - baseline,
    }


def failures(report: dict) -> list[str]:
    """What went wrong in a report of :func:`soak` and/or :func:`cycle_envs`."""
    problems = []
    if "identical" in report and not report["identical"]:
        problems.append("parallel and serial trajectories differ")
    cycles = report.get("cycles")
    if cycles:
        if cycles["clients_left_connected"] or len(cycles["bodies_per_client"]) != 1:
            problems.append(f"PyBullet clients or bodies leak: {cycles}")
        if cycles["rss_growth_mb"] >= MAX_RSS_GROWTH_MB:
            problems.append(f"memory grew {cycles['rss_growth_mb']:.1f} MB")
    return problems


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=200_000, help="env steps in all (0: skip)")
    parser.add_argument("--workers", type=int, default=2, help="parallel envs (2)")
    parser.add_argument("--cycles", type=int, default=0, help="env lifetimes to check (0: skip)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    report = soak(args.steps, args.workers, args.seed) if args.steps > 0 else {}
    if args.cycles > 0:
        report["cycles"] = cycle_envs(args.cycles, seed=args.seed)
    problems = failures(report)
    report["ok"] = not problems
    print(json.dumps(report, indent=None if args.json else 2))
    for problem in problems:
        print(f"soak: FAILED: {problem}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
