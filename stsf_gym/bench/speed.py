"""Env speed as a multiple of real time, each case in its own process pinned to one core.

The follower drives the IRL corridor (on the true pose, or on the estimate where an estimator
runs) for a fixed span of simulated time; the figure is simulated seconds per wall second.
Each case runs in a fresh ``spawn`` process so that its peak memory (``ru_maxrss``) is that of
one env process and no renderer state leaks between cases. The pipeline cases also report the
per-frame latency of each stage: render, detection, motion stereo + STSF update, EKF update.
"""

from __future__ import annotations

import cProfile
import os
import pstats
import resource
import time
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import numpy as np

#: case -> (env overrides, pose source); "truth" drives on info["true_pose"].
CASES: dict[str, tuple[dict, str]] = {
    "a: camera off": ({"camera": {"enabled": False}}, "truth"),
    "b: camera on, EGL": ({"camera": {"renderer": "egl"}}, "truth"),
    "c: camera on, TinyRenderer": ({"camera": {"renderer": "tiny"}}, "truth"),
    "d: camera + detector + STSF": ({"camera": {"control": "pan"}}, "stsf"),
    "e: fast sensor mode + STSF": ({"camera": {"control": "pan", "mode": "fast"}}, "stsf"),
    "camera + detector + EKF": ({"camera": {"control": "pan"}}, "ekf"),
}
PER_STEP_STAGES = ("odometry",)  # estimator stages that run every step, not per frame
ARUCO_FRAMES = 60  # frames kept to time the detector against ArUco


def run_case(
    name: str, sim_seconds: float, seed: int = 0, cpu: int | None = 0, profile: bool = False
) -> dict:
    """Measure one case in a fresh process (pinned to ``cpu`` when given); with ``profile``
    the row also holds cProfile's top functions by own time."""
    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        return pool.submit(_measure, name, sim_seconds, seed, cpu, profile).result()


def _measure(name: str, sim_seconds: float, seed: int, cpu: int | None, profile: bool) -> dict:
    if cpu is not None and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {cpu % os.cpu_count()})
    import gymnasium as gym

    import stsf_gym  # noqa: F401 - registers the ids
    from agents.follower import PathFollower
    from stsf_gym.experiments.episodes import estimator_options
    from stsf_gym.wrappers import PoseEstimateWrapper

    overrides, source = CASES[name]
    env = gym.make("stsf_gym/Corridor-v0", **overrides)
    if source != "truth":
        env = PoseEstimateWrapper(env, source, **estimator_options(source))
    render_time = _time_renders(env.unwrapped)
    follower = PathFollower.for_env(env)
    steps = round(sim_seconds / env.unwrapped.dt)
    obs, info = env.reset(seed=seed)
    profiler = cProfile.Profile() if profile else None
    if profiler is not None:
        profiler.enable()
    frames, kept, start = 0, [], time.perf_counter()
    for _ in range(steps):
        pose = info["true_pose"] if source == "truth" else obs["pose"]
        obs, _, terminated, truncated, info = env.step(follower.act(pose))
        if obs["image_new"]:
            frames += 1
            if "image" in obs and source != "truth" and len(kept) < ARUCO_FRAMES:
                kept.append(obs["image"])
        if terminated or truncated:
            obs, info = env.reset()
    wall = time.perf_counter() - start
    if profiler is not None:
        profiler.disable()
    stages = {"render": render_time["total"]} if render_time["count"] else {}
    if source != "truth":
        timings = env.estimator.timings
        stages["detect"] = timings["detect"]
        stages[f"{source} update"] = sum(
            v for k, v in timings.items() if k not in ("detect", *PER_STEP_STAGES)
        )
    row = {
        "case": name,
        "renderer": env.unwrapped.renderer,
        "steps": steps,
        "wall_s": wall,
        "x_real_time": steps * env.unwrapped.dt / wall,
        "steps_per_s": steps / wall,
        "camera_frames": frames,
        "ms_per_frame": {k: 1e3 * v / max(frames, 1) for k, v in stages.items()},
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }
    if profiler is not None:
        row["profile"] = top_functions(profiler, wall)
    if kept:
        row["detector_vs_aruco"] = detector_vs_aruco(kept, env.unwrapped.config.world)
    env.close()
    return row


def top_functions(profiler: cProfile.Profile, wall: float, count: int = 12) -> list[dict]:
    """The functions with the most own time: share of the wall time, calls, cumulative s."""
    stats = pstats.Stats(profiler).stats
    rows = sorted(stats.items(), key=lambda item: item[1][2], reverse=True)[:count]
    return [
        {
            "function": f"{Path(file).name}:{line}({func})" if line else func,
            "own_share": own / wall,
            "calls": calls,
            "cumulative_s": cumulative,
        }
        for (file, line, func), (_, calls, own, cumulative, _) in rows
    ]


def detector_vs_aruco(images: list[np.ndarray], world, rounds: int = 3) -> dict:
    """Best-of-``rounds`` ms per frame of the landmark detector and of ArUco ``detectMarkers``."""
    import cv2

    from stsf_gym.vision.detector import LandmarkDetector

    detector = LandmarkDetector(world.landmark_pattern, valid_ids={lm.id for lm in world.landmarks})
    greys = [cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) for image in images]
    aruco = cv2.aruco.ArucoDetector(
        cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50), cv2.aruco.DetectorParameters()
    )

    def best_ms(fn, frames) -> float:
        fn(frames[0])  # warm-up
        times = []
        for _ in range(rounds):
            t0 = time.perf_counter()
            for frame in frames:
                fn(frame)
            times.append((time.perf_counter() - t0) / len(frames) * 1e3)
        return min(times)

    ours = best_ms(detector.detect, images)
    theirs = best_ms(aruco.detectMarkers, greys)
    return {"frames": len(images), "detector_ms": ours, "aruco_ms": theirs, "ratio": ours / theirs}


def _time_renders(env) -> dict:
    """Wrap the env's camera render so its wall time is summed (benchmark instrumentation)."""
    totals = defaultdict(float)
    render = env._render_camera

    def timed_render():
        t0 = time.perf_counter()
        image = render()
        totals["total"] += time.perf_counter() - t0
        totals["count"] += 1
        return image

    env._render_camera = timed_render
    return totals


def vector_scaling(steps: int, seed: int = 0) -> dict:
    """Throughput of ``AsyncVectorEnv`` with 1 and 2 workers (fast-mode STSF pipeline)."""
    import gymnasium as gym

    import stsf_gym  # noqa: F401

    rows = {}
    for workers in (1, 2):
        fns = [
            lambda: gym.make("stsf_gym/Corridor-STSF-v0", camera__mode="fast")
            for _ in range(workers)
        ]
        envs = gym.vector.AsyncVectorEnv(fns, context="spawn")
        envs.reset(seed=seed)
        actions = np.tile(np.array([0.5, 0.05], np.float32), (workers, 1))
        start = time.perf_counter()
        for _ in range(steps):
            envs.step(actions)
        rows[workers] = steps * workers / (time.perf_counter() - start)
        envs.close()
    return {
        "steps_per_s_1_worker": rows[1],
        "steps_per_s_2_workers": rows[2],
        "speed_up": rows[2] / rows[1],
    }
