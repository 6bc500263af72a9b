"""Dead-reckoning drift over the straight 10 m at 12.2 cm/s (the paper's sect. 4.3: about 40 cm).

    python benchmarks/odometry_drift.py [--seeds 20] [--json]

The follower drives on the true pose (so the robot really goes straight) while the wheel
encoders are dead-reckoned; reports the final position error and the largest x / y errors.
"""

from __future__ import annotations

import argparse
import json

import gymnasium as gym
import numpy as np
from tqdm import tqdm

import stsf_gym  # noqa: F401
from stsf_gym.agents.follower import PathFollower
from stsf_gym.estimators.odometry_model import integrate_wheel_travel
from stsf_gym.io import markdown_table


def drift(seed: int) -> dict:
    env = gym.make("stsf_gym/Straight10m-v0", camera__enabled=False, world={"goal_radius": 0.05})
    follower = PathFollower.for_env(env)
    obs, info = env.reset(seed=seed)
    calibration = env.unwrapped.odometry_calibration
    estimate, worst = info["true_pose"].copy(), np.zeros(2)
    while info["true_pose"][0] < 10.0:
        obs, _, terminated, truncated, info = env.step(follower.act(info["true_pose"]))
        d_left, d_right = calibration.wheel_travel(obs["encoders"])
        estimate = integrate_wheel_travel(estimate, d_left, d_right, calibration.wheelbase)
        worst = np.maximum(worst, np.abs(estimate[:2] - info["true_pose"][:2]))
        if terminated or truncated:
            break
    env.close()
    final = float(np.hypot(*(estimate[:2] - info["true_pose"][:2])))
    return {
        "seed": seed,
        "final error (m)": final,
        "max |x err| (m)": worst[0],
        "max |y err| (m)": worst[1],
        "time (s)": info["sim_time"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = [drift(seed) for seed in tqdm(range(args.seeds), desc="seeds")]
    finals = np.array([r["final error (m)"] for r in rows])
    summary = {
        "median final error (m)": float(np.median(finals)),
        "mean final error (m)": float(finals.mean()),
        "p90 final error (m)": float(np.percentile(finals, 90)),
    }
    if args.json:
        print(json.dumps({"summary": summary, "runs": rows}, indent=2))
    else:
        print(markdown_table(rows) + "\n" + markdown_table([summary]))


if __name__ == "__main__":
    main()
