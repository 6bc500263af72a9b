"""Fewer physics substeps or solver iterations: what a step saves and what fidelity it loses.

For each ``physics_hz / solver iterations`` pair, the episodes of the simulation's fidelity
tests (``tests/envs/test_robot.py``) with every metric read out instead of asserted: perfect
encoders dead-reckoning a 30 s spin and a 30 s weave (heading drift, position drift per metre,
the chassis's worst tilt from level while turning), a full-speed ramp from rest (distance over
what the acceleration limit gives), and the time of one ``stepSimulation`` in a suite world
(the least of five rounds of 600, so other jobs on the machine disturb it less), times the
substeps of a 0.1 s step.

Usage::

    python benchmarks/physics_rate.py [--rates 60/50,60/20,60/10,30/50,20/50]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.envs import simulator
from stsf_gym.estimators.odometry_model import integrate_wheel_travel

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "envs"))
from helpers import NOISE_FREE_ENCODERS
from test_robot import STRAIGHT, mount_error, reversing_turns

LEVEL_LIMIT = 0.5e-3  # m and rad: the level-chassis test's bound
RAMP_TOLERANCE = 0.1  # the ramp test's relative tolerance


DEFAULT_PHYSICS = simulator.Simulator._set_physics


def _with_iterations(iterations: int) -> None:
    """Every simulator made from now on uses ``iterations`` solver iterations."""

    def set_physics(self) -> None:
        DEFAULT_PHYSICS(self)
        self.client.setPhysicsEngineParameter(numSolverIterations=iterations)

    simulator.Simulator._set_physics = set_physics


def dead_reckoning(hz: float, forward: float) -> tuple[float, float, float]:
    """Heading drift (deg), position drift per metre driven, worst tilt (rad) of a 30 s run."""
    env = gym.make(STRAIGHT, sim={"physics_hz": hz}, camera__enabled=False, **NOISE_FREE_ENCODERS)
    _, info = env.reset(seed=0, options={"start_pose": [0.5, -0.85, -0.1]})
    calibration = env.unwrapped.odometry_calibration
    estimate, previous, distance, tilt = info["true_pose"].copy(), info["true_pose"], 0.0, 0.0
    for action in reversing_turns(forward):
        obs, _, _, _, info = env.step(np.float32(action))
        estimate = integrate_wheel_travel(
            estimate, *calibration.wheel_travel(obs["encoders"]), calibration.wheelbase
        )
        distance += float(np.hypot(*(info["true_pose"][:2] - previous[:2])))
        previous = info["true_pose"]
        tilt = max(tilt, mount_error(env, info)[1])
    env.close()
    heading = abs(math.degrees(math.remainder(estimate[2] - info["true_pose"][2], math.tau)))
    drift = float(np.hypot(*(estimate[:2] - info["true_pose"][:2]))) / max(distance, 1e-9)
    return heading, drift, tilt


def ramp(hz: float, steps: int = 8) -> float:
    """Distance of a full-speed start from rest over the acceleration limit's distance."""
    env = gym.make(STRAIGHT, sim={"physics_hz": hz}, camera={"enabled": False})
    _, info = env.reset(seed=0)
    start = info["true_pose"][:2]
    for _ in range(steps):
        _, _, _, _, info = env.step(np.float32([1.0, 0.0]))
    limit = env.unwrapped.config.robot.max_acceleration
    expected = 0.5 * limit * (steps * env.unwrapped.dt) ** 2
    env.close()
    return float(np.hypot(*(info["true_pose"][:2] - start))) / expected


def step_ms(hz: float, rounds: int = 5, steps: int = 600) -> float:
    """Milliseconds of physics per 0.1 s env step (its ``stepSimulation`` calls) in the
    corridor suite's first test world."""
    env = gym.make("stsf_gym/Suite-Corridor-Truth-v0", sim={"physics_hz": hz})
    env.reset(seed=0)
    client, best = env.unwrapped.sim.client, math.inf
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(steps):
            client.stepSimulation()
        best = min(best, (time.perf_counter() - start) / steps)
    substeps = round(env.unwrapped.dt * hz)
    env.close()
    return best * substeps * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rates", default="60/50,60/20,60/10,30/50,20/50")
    args = parser.parse_args()
    print(
        "| physics_hz / solver iterations | physics ms per step | heading drift, spin / weave "
        "(deg) | position drift per m, weave | worst tilt turning (mrad) | ramp / limit's | "
        "fidelity tests |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for pair in args.rates.split(","):
        hz, iterations = (float(part) for part in pair.split("/"))
        _with_iterations(int(iterations))
        spin, weave, ratio = dead_reckoning(hz, 0.0), dead_reckoning(hz, 1.0), ramp(hz)
        tilt = max(spin[2], weave[2])
        failed = [
            name
            for name, bad in (
                ("dead reckoning", max(spin[0], weave[0]) >= 1.0 or weave[1] > 0.01),
                ("level chassis", tilt >= LEVEL_LIMIT),
                ("ramp", abs(ratio - 1) > RAMP_TOLERANCE),
            )
            if bad
        ]
        print(
            f"| {hz:g} / {iterations:g} | {step_ms(hz):.3f} | {spin[0]:.2f} / {weave[0]:.2f} | "
            f"{weave[1]:.4f} | {tilt * 1e3:.2f} | {ratio:.2f} | "
            f"{'fail: ' + ', '.join(failed) if failed else 'pass'} |"
        )


if __name__ == "__main__":
    main()
