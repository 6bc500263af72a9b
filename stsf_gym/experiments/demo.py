"""``stsf-gym demo``: a short scripted drive down the IRL corridor, reporting what the sensors saw.

The path follower drives on the true pose (privileged; the estimators replace it later) while
the wheel encoders are dead-reckoned alongside, so the table shows odometry drifting away from
the truth, what the sonar ring measured, and which landmarks the camera had in view.
"""

from __future__ import annotations

import time
from pathlib import Path

import gymnasium as gym
import numpy as np
from tqdm import tqdm

import stsf_gym  # noqa: F401 - registers the env ids
from agents.follower import PathFollower
from stsf_gym.estimators.odometry import integrate_wheel_travel
from stsf_gym.io import markdown_table, save_figure, write_atomic, write_json

REPORT_EVERY_S = 10.0


def run_demo(
    out: str | Path,
    seed: int = 0,
    seconds: float = 90.0,
    env_id: str = "stsf_gym/Corridor-v0",
    config: str | dict | None = None,
    **overrides,
) -> dict:
    """Drive for ``seconds`` of simulated time; write ``summary.json``, ``summary.md`` and
    ``demo.png`` to ``out`` and return the summary."""
    env = gym.make(env_id, config=config, **overrides)
    try:
        summary = _drive(env, seed, seconds)
        summary["figure"] = str(_plot(env.unwrapped, summary, Path(out) / "demo.png"))
    finally:
        env.close()
    trace = summary.pop("trace")
    write_json(Path(out) / "summary.json", summary)
    write_atomic(Path(out) / "summary.md", _markdown(summary))
    summary["trace"] = trace
    return summary


def _drive(env, seed: int, seconds: float) -> dict:
    unwrapped = env.unwrapped
    follower = PathFollower.for_env(env)
    obs, info = env.reset(seed=seed)
    calibration = unwrapped.odometry_calibration
    odometry = info["true_pose"].copy()
    trace = {"true": [info["true_pose"]], "odometry": [odometry], "sonar": [obs["sonar"]]}
    rows, frames, frames_with_landmark, seen = [], 1, 0, set()
    steps = round(seconds / unwrapped.dt)
    start = time.perf_counter()
    terminated = truncated = False
    for step in tqdm(range(1, steps + 1), desc="demo drive", unit="step", leave=False):
        obs, _, terminated, truncated, info = env.step(follower.act(info["true_pose"]))
        d_left, d_right = calibration.wheel_travel(obs["encoders"])
        odometry = integrate_wheel_travel(odometry, d_left, d_right, calibration.wheelbase)
        in_view = unwrapped.landmarks_in_view() if obs["image_new"] else []
        frames += int(obs["image_new"])
        frames_with_landmark += int(bool(in_view))
        seen.update(in_view)
        for key, value in (
            ("true", info["true_pose"]),
            ("odometry", odometry),
            ("sonar", obs["sonar"]),
        ):
            trace[key].append(value)
        if (
            step * unwrapped.dt % REPORT_EVERY_S < unwrapped.dt / 2
            or step == steps
            or terminated
            or truncated
        ):
            rows.append(_row(info, odometry, obs["sonar"], frames, in_view))
        if terminated or truncated:
            break
    wall = time.perf_counter() - start
    sim_time = info["sim_time"]
    return {
        "env_id": env.spec.id if env.spec else "",
        "seed": seed,
        "renderer": unwrapped.renderer,
        "control_dt_s": unwrapped.dt,
        "sim_time_s": sim_time,
        "wall_time_s": wall,
        "real_time_factor": sim_time / wall,
        "steps_per_s": step / wall,
        "distance_travelled_m": info["distance_travelled"],
        "camera_frames": frames,
        "frames_with_landmark": frames_with_landmark,
        "landmarks_seen": sorted(seen),
        "odometry_error_m": float(np.hypot(*(odometry[:2] - info["true_pose"][:2]))),
        "outcome": "collision" if info["collision"] else "goal" if terminated else "time",
        "rows": rows,
        "trace": {k: np.asarray(v) for k, v in trace.items()},
        "last_image": obs["image"],
    }


def _row(info: dict, odometry: np.ndarray, sonar: np.ndarray, frames: int, in_view) -> dict:
    x, y, yaw = info["true_pose"]
    return {
        "t (s)": round(info["sim_time"], 1),
        "true x, y (m)": f"{x:.2f}, {y:.2f}",
        "yaw (deg)": round(float(np.degrees(yaw)), 1),
        "odometry error (m)": round(float(np.hypot(*(odometry[:2] - (x, y)))), 3),
        "sonar front (m)": round(float(sonar[0]), 2),
        "sonar min (m)": round(float(sonar.min()), 2),
        "frames": frames,
        "landmarks in view": ",".join(map(str, in_view)) or "-",
    }


def _markdown(summary: dict) -> str:
    head = (
        f"# stsf-gym demo ({summary['env_id']}, seed {summary['seed']})\n\n"
        f"Renderer {summary['renderer']}; {summary['sim_time_s']:.1f} s simulated in "
        f"{summary['wall_time_s']:.1f} s ({summary['real_time_factor']:.1f}x real time); "
        f"travelled {summary['distance_travelled_m']:.2f} m; outcome: {summary['outcome']}; "
        f"dead-reckoning error {summary['odometry_error_m']:.3f} m; "
        f"{summary['frames_with_landmark']} of {summary['camera_frames']} frames with a landmark "
        f"in view (ids seen: {summary['landmarks_seen']}).\n\n"
    )
    return head + markdown_table(summary["rows"])


def _plot(env, summary: dict, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    trace = summary["trace"]
    fig, (ax_map, ax_img) = plt.subplots(1, 2, figsize=(13, 5), width_ratios=[1.5, 1])
    draw_world_config(ax_map, env.config.world)
    ax_map.plot(*trace["true"][:, :2].T, color="tab:green", label="true")
    ax_map.plot(*trace["odometry"][:, :2].T, color="tab:red", ls="--", label="dead reckoning")
    pose, ranges = trace["true"][-1], trace["sonar"][-1]
    angles = pose[2] + env.sonar.axes
    ax_map.scatter(
        pose[0] + ranges * np.cos(angles),
        pose[1] + ranges * np.sin(angles),
        s=8,
        color="tab:blue",
        label="sonar (last)",
    )
    ax_map.legend(loc="best", fontsize=8)
    ax_map.set_title(f"{summary['env_id']}: {summary['distance_travelled_m']:.1f} m driven")
    ax_img.imshow(summary["last_image"])
    ax_img.set_title(f"last camera frame ({env.renderer})")
    ax_img.axis("off")
    try:
        return save_figure(fig, path)
    finally:
        plt.close(fig)


def draw_world_config(ax, world) -> None:
    """Walls, obstacles, path, goal and landmarks of a world config on a top-down axis."""
    for x1, y1, x2, y2 in world.walls:
        ax.plot([x1, x2], [y1, y2], color="0.3", lw=3, solid_capstyle="butt")
    for obstacle in world.obstacles:
        ax.scatter(*obstacle.position, marker="s", s=60, color="tab:brown")
    path = np.asarray(world.path)
    ax.plot(*path.T, color="0.6", ls=":", label="path")
    ax.scatter(*world.goal, marker="*", s=150, color="gold", zorder=5, label="goal")
    for landmark in world.landmarks:
        at = np.asarray(landmark.at)
        normal = np.array(
            [np.cos(np.radians(landmark.facing_deg)), np.sin(np.radians(landmark.facing_deg))]
        )
        ax.scatter(*at, marker="s", s=30, color="k", zorder=5)
        ax.annotate(str(landmark.id), at + 0.4 * normal, ha="center", va="center", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
