"""Where does an agent miss? Each benchmark row's misses split by the goal's bearing off the route.

A policy that steers by the goal's straight line fails where that line and the route part:
on a world whose goal lies far off the route's first leg (a route that turns round). This
reads a finished ``stsf-gym benchmark`` results file, computes for each test world the angle
between the route's first leg and the straight line from its start to the final goal, and
counts each row's episodes and misses on the worlds beyond ``--angle`` degrees and within it.

Usage::

    python benchmarks/goal_bearing.py OUT/SUITE/results.json [--angle 90] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from stsf_gym.envs.generated_env import episode_config
from stsf_gym.envs.suite import load_suite
from stsf_gym.envs.task import PathTask


def goal_bearing_deg(suite: str, world_seed: int) -> float:
    """Degrees between the first leg of test world ``world_seed``'s route and the straight
    line from its start to its last goal."""
    cfg = episode_config("generated:test", world_seed, load_suite(suite).episode_env)
    path = np.asarray(cfg.world.path, dtype=float)
    goal = np.asarray(PathTask(cfg.world, cfg.reward, cfg.task).goals[-1], dtype=float)
    leg, line = path[1] - path[0], goal - path[0]
    return abs(math.degrees(math.atan2(leg[0] * line[1] - leg[1] * line[0], leg @ line)))


def split_misses(results: dict, angle: float) -> list[dict]:
    """Per row (agent, pose source): episodes and misses on worlds beyond and within ``angle``."""
    seeds = {seed for row in results["rows"] for seed in row["seeds"]}
    bearings = {seed: goal_bearing_deg(results["suite"], seed) for seed in seeds}
    rows = []
    for row in results["rows"]:
        far = np.array([bearings[seed] > angle for seed in row["seeds"]])
        missed = np.array(row["success_rate"]["values"]) < 1.0
        rows.append(
            {
                "agent": row["agent"],
                "estimator": row["estimator"],
                "beyond": {"worlds": int(far.sum()), "misses": int((missed & far).sum())},
                "within": {"worlds": int((~far).sum()), "misses": int((missed & ~far).sum())},
            }
        )
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, help="a benchmark's results.json")
    parser.add_argument("--angle", type=float, default=90.0, help="degrees (default 90)")
    parser.add_argument("--json", action="store_true", help="print the numbers as JSON")
    args = parser.parse_args(argv)
    rows = split_misses(json.loads(args.results.read_text()), args.angle)
    if args.json:
        print(json.dumps(rows, indent=1))
        return
    for row in rows:
        beyond, within = row["beyond"], row["within"]
        print(
            f"{row['agent']} on {row['estimator']}: beyond {args.angle:g} deg "
            f"{beyond['misses']} misses on {beyond['worlds']} worlds, within "
            f"{within['misses']} on {within['worlds']}"
        )


if __name__ == "__main__":
    main()
