"""Env speed as a multiple of real time: the follower drives the IRL corridor on one core.

    python benchmarks/env_speed.py [--steps 600] [--json]

Configurations: camera off; camera on with the automatic renderer (EGL where it loads); camera
on with TinyRenderer. Prints a Markdown table (or JSON) of steps/s and simulated s per wall s.
"""

from __future__ import annotations

import argparse
import json
import time

import gymnasium as gym

import stsf_gym  # noqa: F401
from agents.follower import PathFollower
from stsf_gym.io import markdown_table

CASES = {
    "camera off": {"camera__enabled": False},
    "camera on (auto renderer)": {},
    "camera on (TinyRenderer)": {"camera__renderer": "tiny"},
}


def measure(steps: int, seed: int, **overrides) -> dict:
    env = gym.make("stsf_gym/Corridor-v0", **overrides)
    follower = PathFollower.for_env(env)
    _, info = env.reset(seed=seed)
    start = time.perf_counter()
    for _ in range(steps):
        _, _, terminated, truncated, info = env.step(follower.act(info["true_pose"]))
        if terminated or truncated:
            _, info = env.reset()
    wall = time.perf_counter() - start
    row = {
        "renderer": env.unwrapped.renderer,
        "steps/s": steps / wall,
        "x real time": steps * env.unwrapped.dt / wall,
    }
    env.close()
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=600)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = [{"case": name, **measure(args.steps, args.seed, **kw)} for name, kw in CASES.items()]
    print(json.dumps(rows, indent=2) if args.json else markdown_table(rows))


if __name__ == "__main__":
    main()
