"""Generated worlds in a row: every one passes the world checks, keeps its guarantees, builds.

    python benchmarks/generated_worlds.py --count 1000 --out out/bench/generated_worlds.json

For each world seed (from ``--first``): generate it; build the env config from its YAML tree
(the world checks and the clearance checks of :mod:`stsf_gym.envs.worlds.spec`); recheck that
every path point sees a landmark (:mod:`stsf_gym.envs.worlds.visibility`) and that the path is
passable; build its bodies in a PyBullet simulator. Then the rebuild cost in the env:
``reset(seed=k)`` of ``stsf_gym/Generated-v0`` onto a new world each time (generation and build),
against a reset that keeps the world and against the steps of an episode.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
from tqdm import tqdm

import stsf_gym  # noqa: F401
from stsf_gym.envs.config import load_config
from stsf_gym.envs.simulator import Simulator
from stsf_gym.envs.worlds.corridor import CorridorWorld
from stsf_gym.envs.worlds.generator import generate_world, path_clearance, world_tree
from stsf_gym.envs.worlds.generator_config import load_generator_config
from stsf_gym.io import write_json


def check_worlds(first: int, count: int) -> dict:
    env_cfg, gen = load_config(), load_generator_config()
    sim = Simulator(env_cfg.sim.physics_hz, "none")
    failures, generate_s, build_s, landmarks, lengths = [], [], [], [], []
    need = env_cfg.robot.body_radius + gen.clutter.path_clearance - 1e-6
    try:
        for seed in tqdm(range(first, first + count), desc="generated worlds"):
            try:
                started = time.perf_counter()
                tree = world_tree(seed, gen, env_cfg)
                generate_s.append(time.perf_counter() - started)
                world = load_config(world=tree).world  # every world and clearance check
                assert world == generate_world(seed, gen, env_cfg), "not deterministic"
                assert path_clearance(world) >= need, "path not passable"
                started = time.perf_counter()
                sim.clear()
                CorridorWorld(sim, world)
                build_s.append(time.perf_counter() - started)
                landmarks.append(len(world.landmarks))
                path = np.asarray(world.path)
                lengths.append(float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1))))
            except Exception as err:  # counted and reported, the run goes on
                failures.append({"seed": seed, "error": f"{type(err).__name__}: {err}"})
    finally:
        sim.close()
    return {
        "worlds": count,
        "first_seed": first,
        "failures": failures,
        "generate_ms": _stats(1000 * np.array(generate_s)),
        "build_ms": _stats(1000 * np.array(build_s)),
        "landmarks": _stats(np.array(landmarks)),
        "path_length_m": _stats(np.array(lengths)),
    }


def rebuild_cost(resets: int) -> dict:
    """Wall time of resets onto new worlds, onto the same world, and of one env step."""
    env = gym.make("stsf_gym/Generated-v0", split="test", camera__mode="fast")
    try:
        env.reset(seed=0)
        new, same = [], []
        for k in range(1, resets + 1):
            started = time.perf_counter()
            env.reset(seed=k)
            new.append(time.perf_counter() - started)
            started = time.perf_counter()
            env.reset(seed=k)
            same.append(time.perf_counter() - started)
        started, steps = time.perf_counter(), 500
        for _ in range(steps):
            env.step(np.array([0.5, 0.0], np.float32))
        step = (time.perf_counter() - started) / steps
    finally:
        env.close()
    return {
        "reset_new_world_ms": _stats(1000 * np.array(new)),
        "reset_same_world_ms": _stats(1000 * np.array(same)),
        "step_ms": 1000 * step,
        "new_world_reset_in_steps": float(np.mean(new) / step),
    }


def _stats(values: np.ndarray) -> dict:
    if len(values) == 0:
        return {"mean": None, "std": None, "max": None, "count": 0}
    return {
        "mean": float(values.mean()),
        "std": float(values.std()),
        "max": float(values.max()),
        "count": len(values),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=1000, help="worlds in a row (1000)")
    parser.add_argument("--first", type=int, default=0, help="first world seed (0)")
    parser.add_argument("--resets", type=int, default=20, help="env resets timed (20)")
    parser.add_argument("--out", type=Path, default=Path("out/bench/generated_worlds.json"))
    args = parser.parse_args()
    result = {**check_worlds(args.first, args.count), **rebuild_cost(args.resets)}
    write_json(args.out, result)
    print(
        f"{result['worlds'] - len(result['failures'])}/{result['worlds']} worlds passed and "
        f"built; generate {result['generate_ms']['mean']:.0f} ms, build "
        f"{result['build_ms']['mean']:.0f} ms; env reset onto a new world "
        f"{result['reset_new_world_ms']['mean']:.0f} ms (same world "
        f"{result['reset_same_world_ms']['mean']:.1f} ms) = "
        f"{result['new_world_reset_in_steps']:.0f} env steps of {result['step_ms']:.2f} ms"
    )
    for failure in result["failures"]:
        print(f"  world {failure['seed']}: {failure['error']}")
    print(f"Wrote {args.out}")


if __name__ == "__main__":
    main()
