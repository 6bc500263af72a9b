"""Env speed as a multiple of real time, each case in its own process pinned to one core.

The follower drives the IRL corridor (on the true pose, or on the estimate where an estimator
runs) for a fixed span of simulated time; the figures are simulated seconds per wall second and
per second of the process's CPU time.
Each case runs in a fresh ``spawn`` process so that its peak memory (``ru_maxrss``) is that of
one env process and no renderer state leaks between cases. The pipeline cases also report the
per-frame latency of each stage: camera frame (render, lens, sensor), detection, motion stereo
+ STSF update, EKF update, and the references' (smoother per frame, MCL per step, in the
fast sensor mode). :func:`render_latency` times each renderer alone at two sizes. Each process
reports the package modules it loaded, for the bench's provenance.
"""

from __future__ import annotations

import cProfile
import os
import pstats
import resource
import time
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from functools import partial
from multiprocessing import get_context
from pathlib import Path

import numpy as np
from tqdm import tqdm

from stsf_gym.results.code_identity import run_reporting_modules, worker_result

#: case -> (env overrides, pose source); "truth" drives on info["true_pose"].
CASES: dict[str, tuple[dict, str]] = {
    "a: camera off": ({"camera": {"enabled": False}}, "truth"),
    "b: camera on, GL": ({"camera": {"renderer": "gl"}}, "truth"),
    "c: camera on, PyBullet EGL": ({"camera": {"renderer": "egl"}}, "truth"),
    "d: camera on, TinyRenderer": ({"camera": {"renderer": "tiny"}}, "truth"),
    "e: camera + detector + STSF": ({"camera": {"control": "pan"}}, "stsf"),
    "f: camera + detector + EKF": ({"camera": {"control": "pan"}}, "ekf"),
    "g: fast sensor mode + STSF": ({"camera": {"control": "pan", "mode": "fast"}}, "stsf"),
    "h: fast sensor mode + EKF": ({"camera": {"control": "pan", "mode": "fast"}}, "ekf"),
    "i: fast sensor mode + smoother": ({"camera": {"control": "pan", "mode": "fast"}}, "smoother"),
    "j: fast sensor mode + MCL": ({"camera": {"control": "pan", "mode": "fast"}}, "mcl"),
}
#: The cases whose env is cheap: a longer, steadier span of simulated time.
FAST_CASES = ("a:", "g:", "h:", "i:", "j:")
PROFILED_CASE = "e: camera + detector + STSF"  # the case whose cProfile bench.md shows
RENDERERS = ("gl", "egl", "tiny")
RENDER_SIZES = ((320, 240), (640, 480))
PER_STEP_STAGES = ("odometry",)  # estimator stages that run every step, not per frame
ARUCO_FRAMES = 60  # frames kept to time the detector against ArUco


def run_case(
    name: str, sim_seconds: float, seed: int = 0, cpu: int | None = 0, profile: bool = False
) -> dict:
    """Measure one case in a fresh process (pinned to ``cpu`` when given); with ``profile``
    the row also holds cProfile's top functions by own time."""
    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        reply = pool.submit(run_reporting_modules, _measure, name, sim_seconds, seed, cpu, profile)
        return worker_result(reply.result())


def _measure(name: str, sim_seconds: float, seed: int, cpu: int | None, profile: bool) -> dict:
    if cpu is not None and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {cpu % os.cpu_count()})
    import gymnasium as gym

    import stsf_gym  # noqa: F401 - registers the ids
    from stsf_gym.agents.follower import PathFollower
    from stsf_gym.wrappers import CameraPointingWrapper, PoseEstimateWrapper

    overrides, source = CASES[name]
    env = gym.make("stsf_gym/Corridor-v0", **overrides)
    if source != "truth":  # the estimator's settings from configs/
        env = PoseEstimateWrapper(env, source)
        if env.unwrapped.config.camera.control == "pan":
            env = CameraPointingWrapper(env)
    frame_time = _time_frames(env.unwrapped)
    follower = PathFollower.for_env(env)
    steps = round(sim_seconds / env.unwrapped.dt)
    obs, info = env.reset(seed=seed)
    kept: list = []
    wall, cpu, frames, obs, info = _drive(env, follower, source, steps, obs, info, kept)
    stages = {"camera frame": frame_time["total"]} if frame_time["count"] else {}
    if source != "truth":
        timings = env.get_wrapper_attr("estimator").timings
        stages["detect"] = timings["detect"]
        stages[f"{source} update"] = sum(
            v for k, v in timings.items() if k not in ("detect", *PER_STEP_STAGES)
        )
    row = {
        "case": name,
        "renderer": env.unwrapped.renderer,
        "steps": steps,
        "wall_s": wall,
        "cpu_s": cpu,
        "x_real_time": steps * env.unwrapped.dt / wall,
        # simulated s per s of the process's CPU time (its llvmpipe threads included): what
        # one core costs, less sensitive than wall time to other jobs on a shared machine
        "x_real_time_cpu": steps * env.unwrapped.dt / cpu,
        "steps_per_s": steps / wall,
        "camera_frames": frames,
        "renders_per_frame": frame_time["renders"] / frame_time["count"]
        if frame_time["count"]
        else None,
        "ms_per_frame": {k: 1e3 * v / max(frames, 1) for k, v in stages.items()},
        # every stage of the estimator (odometry, detection, update) per control step
        "estimator_ms_per_step": None
        if source == "truth"
        else 1e3 * sum(env.get_wrapper_attr("estimator").timings.values()) / steps,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }
    if profile:  # a second drive of the same length: the profiler's overhead stays out of the rows
        profiler = cProfile.Profile()
        profiler.enable()
        profiled_wall, *_ = _drive(env, follower, source, steps, obs, info, None)
        profiler.disable()
        row["profile"] = top_functions(profiler, profiled_wall)
    if kept:
        row["detector_vs_aruco"] = detector_vs_aruco(
            kept, env.unwrapped.config.world, env.get_wrapper_attr("estimator").detector
        )
    env.close()
    return row


def _drive(env, follower, source: str, steps: int, obs, info, kept: list | None):
    """The follower drives ``steps`` steps (on the truth or the estimate); returns wall s,
    CPU s, camera frames and the last observation and info. ``kept`` collects the first
    rendered frames with the predictions the estimator's detector was given."""
    frames, start, start_cpu = 0, time.perf_counter(), time.process_time()
    for _ in range(steps):
        pose = info["true_pose"] if source == "truth" else obs["pose"]
        obs, _, terminated, truncated, info = env.step(follower.act(pose))
        if obs["image_new"]:
            frames += 1
            keep = kept is not None and len(kept) < ARUCO_FRAMES
            if keep and "image" in obs and source != "truth":
                kept.append((obs["image"], env.get_wrapper_attr("estimator").detector.predictions))
        if terminated or truncated:
            obs, info = env.reset()
    return time.perf_counter() - start, time.process_time() - start_cpu, frames, obs, info


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


def detector_vs_aruco(frames: list[tuple], world, live, rounds: int = 3) -> dict:
    """Best-of-``rounds`` ms per frame, on the same frames (``(image, predictions)``, the first
    of the drive), of the plain landmark detector, of the estimator's whole detection stage
    replayed (``pipeline_ms``: a fresh copy of its :class:`FrameDetector` given the predictions
    it was given live, so track-aided matching and undistortion included) and of ArUco
    ``detectMarkers``."""
    import cv2

    from stsf_gym.estimators.frame_detector import FrameDetector
    from stsf_gym.vision.detector import LandmarkDetector

    detector = LandmarkDetector(world.landmark_pattern, valid_ids={lm.id for lm in world.landmarks})
    images = [image for image, _ in frames]
    greys = [cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) for image in images]
    aruco = cv2.aruco.ArucoDetector(
        cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50), cv2.aruco.DetectorParameters()
    )

    def replay(_) -> None:
        pipeline = FrameDetector(live.pattern, live.valid_ids, live.calibration, live.matcher)
        for image, predictions in frames:
            pipeline({"image": image}, predictions)

    def best_ms(fn, items, per_item: bool = True) -> float:
        fn(items[0])  # warm-up
        times = []
        for _ in range(rounds):
            t0 = time.perf_counter()
            if per_item:
                for item in items:
                    fn(item)
            else:
                fn(items)
            times.append((time.perf_counter() - t0) / len(items) * 1e3)
        return min(times)

    ours = best_ms(detector.detect, images)
    pipeline = best_ms(replay, frames, per_item=False)
    theirs = best_ms(aruco.detectMarkers, greys)
    return {
        "frames": len(images),
        "detector_ms": ours,
        "pipeline_ms": pipeline,
        "aruco_ms": theirs,
        "ratio": ours / theirs,
        "pipeline_ratio": pipeline / theirs,
    }


def _time_frames(env) -> dict:
    """Wrap the env's camera capture so its wall time is summed, and the simulator's render so
    its calls are counted (motion blur renders several times a frame; benchmark
    instrumentation)."""
    totals = defaultdict(float)
    capture, render = env.camera_sensor.capture, env.sim.render

    def counted_render(*args):
        totals["renders"] += 1
        return render(*args)

    env.sim.render = counted_render

    def timed_capture(*args):
        t0 = time.perf_counter()
        capture(*args)
        totals["total"] += time.perf_counter() - t0
        totals["count"] += 1

    env.camera_sensor.capture = timed_capture
    return totals


def render_latency(frames: int = 200, cpu: int | None = 0) -> list[dict]:
    """ms per frame of each renderer alone (``Simulator.render``, the IRL corridor as the
    robot starts, 320x240 and 640x480), each in a fresh process on one core."""
    rows = []
    for renderer in RENDERERS:
        with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
            reply = pool.submit(run_reporting_modules, _render_latency, renderer, frames, cpu)
            rows.append(worker_result(reply.result()))
    return rows


def _render_latency(renderer: str, frames: int, cpu: int | None) -> dict:
    if cpu is not None and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {cpu % os.cpu_count()})
    import gymnasium as gym

    import stsf_gym  # noqa: F401 - registers the ids
    from stsf_gym.envs.sensors.camera import PinholeCamera, view_matrix

    try:
        env = gym.make("stsf_gym/Corridor-v0", camera__renderer=renderer)
    except RuntimeError as err:  # this renderer cannot start here
        return {"renderer": renderer, "error": str(err)}
    u = env.unwrapped
    env.reset(seed=0)
    view = view_matrix(u.robot.camera_pose())
    row = {"renderer": renderer}
    for width, height in RENDER_SIZES:
        cfg = u.config.camera
        camera = PinholeCamera(width, height, cfg.vfov_deg, cfg.near, cfg.far)
        projection = camera.projection_matrix()
        u.sim.render(width, height, view, projection)  # warm-up: buffers made on first use
        start = time.perf_counter()
        for _ in range(frames):
            u.sim.render(width, height, view, projection)
        row[f"ms_{width}x{height}"] = (time.perf_counter() - start) / frames * 1e3
        if renderer == "gl":
            row[f"camera_frame_ms_{width}x{height}"] = _camera_frame_ms(width, height, frames)
    row["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    env.close()
    return row


#: vector-env throughput cases: label -> (env id, overrides)
VECTOR_PIPELINES = {
    "rendered STSF": ("stsf_gym/Corridor-STSF-v0", {}),
    "fast mode STSF": ("stsf_gym/Corridor-STSF-v0", {"camera__mode": "fast"}),
}
VECTOR_KINDS = ("AsyncVectorEnv", "SubprocVecEnv")


def _camera_frame_ms(width: int, height: int, frames: int) -> float:
    """ms per whole camera frame (render, lens, defocus, sensor) of a still camera of this
    size, the paper's camera profile."""
    import gymnasium as gym

    env = gym.make("stsf_gym/Corridor-v0", camera__width=width, camera__height=height)
    u = env.unwrapped
    env.reset(seed=0)
    pose, rng = u.robot.camera_pose(), np.random.default_rng(0)
    u.camera_sensor.capture(pose, rng)  # warm-up
    start = time.perf_counter()
    for _ in range(frames):
        u.camera_sensor.capture(pose, rng)
    elapsed = time.perf_counter() - start
    env.close()
    return elapsed / frames * 1e3


def vector_scaling(steps: int, seed: int = 0) -> list[dict]:
    """Throughput with 1 and 2 workers of Gymnasium's ``AsyncVectorEnv`` and stable-baselines3's
    ``SubprocVecEnv`` (each worker a ``spawn`` process), on the rendered and the fast-mode STSF
    pipelines: steps per second of all workers together, the 2-worker speed-up, and where a
    2-worker vector step's wall time goes (each worker's and the parent's CPU time per step)."""
    rows = []
    runs = [(p, k) for p in VECTOR_PIPELINES for k in VECTOR_KINDS]
    for pipeline, kind in tqdm(runs, desc="vector envs", unit="run"):
        env_id, overrides = VECTOR_PIPELINES[pipeline]
        one = _vector_rate(kind, env_id, overrides, 1, steps, seed)
        two = _vector_rate(kind, env_id, overrides, 2, steps, seed)
        rows.append(
            {
                "pipeline": pipeline,
                "vector env": kind,
                "steps_per_s_1_worker": one["steps_per_s"],
                "steps_per_s_2_workers": two["steps_per_s"],
                "speed_up": two["steps_per_s"] / one["steps_per_s"],
                "wall_ms_per_step_1_worker": one["wall_ms"],
                "worker_cpu_ms_per_step_1_worker": one["worker_cpu_ms"],
                "wall_ms_per_step_2_workers": two["wall_ms"],
                "worker_cpu_ms_per_step_2_workers": two["worker_cpu_ms"],
                "parent_cpu_ms_per_step_2_workers": two["parent_cpu_ms"],
            }
        )
    return rows


def _make_env(env_id: str, overrides: dict):
    """A worker's env (a module-level function: a spawned worker imports this module, and
    with it stsf_gym's registrations)."""
    import gymnasium as gym

    return gym.make(env_id, **overrides)


def _process_cpu_s(pid: int) -> float:
    """CPU seconds (user + system) process ``pid`` has used (Linux ``/proc``; NaN elsewhere)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return float("nan")
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _vector_rate(
    kind: str, env_id: str, overrides: dict, workers: int, steps: int, seed: int
) -> dict:
    """Steps per second of ``workers`` workers together; per vector step its wall time and
    the mean worker's and the parent's CPU time (ms)."""
    import gymnasium as gym

    fns = [partial(_make_env, env_id, overrides) for _ in range(workers)]
    actions = np.tile(np.array([0.5, 0.05], np.float32), (workers, 1))
    if kind == "AsyncVectorEnv":
        envs = gym.vector.AsyncVectorEnv(fns, context="spawn")
        envs.reset(seed=seed)
    else:
        from stable_baselines3.common.vec_env import SubprocVecEnv

        envs = SubprocVecEnv(fns, start_method="spawn")
        envs.seed(seed)
        envs.reset()
    envs.step(actions)  # warm-up: the first frame builds the GL objects
    pids = [p.pid for p in envs.processes]
    worker_cpu = [_process_cpu_s(pid) for pid in pids]
    parent_cpu, start = time.process_time(), time.perf_counter()
    for _ in range(steps):
        envs.step(actions)
    wall = time.perf_counter() - start
    parent_cpu = time.process_time() - parent_cpu
    used = [_process_cpu_s(pid) - cpu for pid, cpu in zip(pids, worker_cpu, strict=True)]
    worker_cpu = float(np.mean(used))
    envs.close()
    return {
        "steps_per_s": steps * workers / wall,
        "wall_ms": wall / steps * 1e3,
        "worker_cpu_ms": worker_cpu / steps * 1e3,
        "parent_cpu_ms": parent_cpu / steps * 1e3,
    }
