"""A world of your own: a U-shaped corridor written as YAML, checked, and driven by the follower.

A world is wall centre lines, a path, a start and the landmark boards (``configs/worlds/`` has
the package's; the keys are :class:`stsf_gym.envs.config.WorldConfig`'s). Any YAML path works
wherever a world is named: ``gym.make(id, world=PATH)``, ``stsf-gym evaluate --world PATH``.
The geometry is checked before anything is built: a board off its wall, a path through a wall
or a start too near one fails naming the file and the key (the second half of ``main``).

    python examples/custom_world.py [--out out/custom_world]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import gymnasium as gym
import numpy as np
import yaml

import stsf_gym  # noqa: F401  (registers the ids)
from stsf_gym.agents.follower import PathFollower
from stsf_gym.validation import ConfigError

#: Two 2 m wide legs joined by a 2 m wide cross leg: walls as centre-line segments [x1, y1, x2, y2].
WORLD = {
    "name": "u_corridor",
    "wall_height": 2.0,
    "wall_thickness": 0.1,
    "walls": [
        [-1.0, -1.0, 9.0, -1.0],  # south wall of the first leg, outer wall of the turn
        [-1.0, 1.0, 7.0, 1.0],  # north wall of the first leg
        [-1.0, -1.0, -1.0, 1.0],  # start cap
        [9.0, -1.0, 9.0, 5.0],  # east wall of the cross leg
        [7.0, 1.0, 7.0, 3.0],  # west wall of the cross leg
        [-1.0, 5.0, 9.0, 5.0],  # north wall of the way back
        [-1.0, 3.0, 7.0, 3.0],  # south wall of the way back
        [-1.0, 3.0, -1.0, 5.0],  # end cap
    ],
    "path": [[0.0, 0.0], [8.0, 0.0], [8.0, 4.0], [0.5, 4.0]],
    "start": [0.0, 0.0, 0.0],
    "goal_radius": 0.4,
    "landmark_height": 0.9,
    "landmark_pattern": {"square_size": 0.05, "pitch": 0.10, "grid": 5, "border": 0.05},
    "landmarks": [
        {"id": 1, "at": [3.0, 1.0], "facing_deg": -90},
        {"id": 2, "at": [6.0, -1.0], "facing_deg": 90},
        {"id": 3, "at": [9.0, 2.0], "facing_deg": 180},
        {"id": 4, "at": [5.0, 3.0], "facing_deg": 90},
        {"id": 5, "at": [2.0, 5.0], "facing_deg": -90},
        {"id": 6, "at": [-1.0, 4.0], "facing_deg": 0},
    ],
    "obstacles": [],
}


def drive(world: Path, seed: int = 0) -> dict:
    """The follower on STSF (fast sensor mode) through ``world``: how the episode ended."""
    env = gym.make("stsf_gym/Corridor-STSF-v0", world=str(world), camera__mode="fast")
    try:
        follower = PathFollower.for_env(env)
        obs, info = env.reset(seed=seed)
        terminated = truncated = False
        while not (terminated or truncated):
            obs, _, terminated, truncated, info = env.step(follower.act(obs["pose"], obs["sonar"]))
        error = float(np.hypot(*(obs["pose"][:2] - info["true_pose"][:2])))
        return {
            "reached_goal": bool(terminated and not info["collision"]),
            "collision": bool(info["collision"]),
            "seconds": float(info["sim_time"]),
            "metres": float(info["distance_travelled"]),
            "final_error_m": error,
        }
    finally:
        env.close()


def main(argv: list[str] | None = None) -> dict:
    """Write the world, drive it, and show the check refusing a broken copy."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/custom_world"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    world = args.out / "u_corridor.yaml"
    world.write_text(yaml.safe_dump(WORLD, sort_keys=False))
    outcome = drive(world)
    print(f"{world}: {outcome}")

    broken = args.out / "broken.yaml"
    board_off_wall = {**WORLD["landmarks"][0], "at": [3.0, 0.5]}
    broken.write_text(
        yaml.safe_dump({**WORLD, "landmarks": [board_off_wall, *WORLD["landmarks"][1:]]})
    )
    try:
        gym.make("stsf_gym/Corridor-v0", world=str(broken)).close()
    except ConfigError as err:
        outcome["broken_world_error"] = str(err)
        print(f"refused before anything was built: {err}")
    return outcome


if __name__ == "__main__":
    main()
