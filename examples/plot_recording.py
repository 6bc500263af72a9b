"""A picture of what a Rerun recording holds, read back with Rerun's own reader (no viewer).

The Rerun viewer needs a display; this draws the same entities with matplotlib: the map
(``world/walls``, ``world/landmarks`` with their ids), the true and estimated trajectories
(``world/trajectory/*``), the position error and NEES on the ``sim_time`` timeline
(``metrics/*``), and one camera frame (``camera/image``) with the detector's boards
(``camera/detections``)::

    stsf-gym demo --record rerun --no-video --out out/demo
    python examples/plot_recording.py out/demo/recordings/irl_corridor-stsf-follower-0.rrd \\
        --out docs/figures/rerun_recording.png
"""

from __future__ import annotations

import argparse
from collections import defaultdict
from pathlib import Path

import cv2
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from rerun.chunk import RrdReader


def read(path: Path) -> tuple[dict, dict]:
    """Static entities (path -> their columns) and temporal ones (path -> rows by time)."""
    static, temporal = {}, defaultdict(dict)
    for chunk in RrdReader(path).stream():
        columns = chunk.to_record_batch().to_pydict()
        if chunk.is_static:
            static.setdefault(chunk.entity_path, {}).update(columns)
            continue
        for i, t in enumerate(columns["sim_time"]):
            row = {k: v[i] for k, v in columns.items() if ":" in k}
            temporal[chunk.entity_path][t.total_seconds()] = row
    return static, temporal


def draw_boxes(ax, boxes: dict, color: str, labels: bool = False) -> None:
    centres = boxes["Boxes3D:centers"][0]
    halves = boxes["Boxes3D:half_sizes"][0]
    angles = [r["angle"] for r in boxes["Boxes3D:rotation_axis_angles"][0]]
    for i, (centre, half, angle) in enumerate(zip(centres, halves, angles, strict=True)):
        corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]]) * half[:2]
        c, s = np.cos(angle), np.sin(angle)
        xy = corners @ np.array([[c, s], [-s, c]]) + centre[:2]
        ax.fill(xy[:, 0], xy[:, 1], color=color)
        if labels:
            ax.annotate(boxes["Boxes3D:labels"][0][i], centre[:2], fontsize=8, color="purple")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("rrd", type=Path)
    parser.add_argument("--out", type=Path, default=Path("rerun_recording.png"))
    args = parser.parse_args()
    static, temporal = read(args.rrd)
    fig = plt.figure(figsize=(13, 7.5))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.6, 1])
    world = fig.add_subplot(grid[:, 0])
    draw_boxes(world, static["/world/walls"], "0.7")
    draw_boxes(world, static["/world/landmarks"], "black", labels=True)
    for entity, columns in static.items():
        if entity.startswith("/world/trajectory/"):
            strip = np.array(columns["LineStrips3D:strips"][0][0])
            world.plot(strip[:, 0], strip[:, 1], label=entity.rsplit("/", 1)[1])
    world.set_aspect("equal")
    world.legend()
    world.set_title(f"world/ (3-D in Rerun; from above here): {args.rrd.name}")
    metrics = fig.add_subplot(grid[0, 1])
    for entity, rows in temporal.items():
        if entity.startswith("/metrics/position_error/") or entity.startswith("/metrics/nees/"):
            times = sorted(rows)
            values = [rows[t]["Scalars:scalars"][0] for t in times]
            metrics.plot(times, values, label=entity[len("/metrics/") :])
    metrics.set_yscale("log")
    metrics.set_xlabel("sim_time (s)")
    metrics.legend()
    metrics.set_title("metrics/ on the sim_time timeline")
    camera = fig.add_subplot(grid[1, 1])
    detections = temporal.get("/camera/detections", {})
    seen = [t for t, row in detections.items() if row["Points2D:positions"]]
    images = temporal.get("/camera/image", {})
    if seen and images:
        t = seen[len(seen) // 2]
        blob = np.frombuffer(bytes(images[t]["EncodedImage:blob"][0]), np.uint8)
        camera.imshow(cv2.cvtColor(cv2.imdecode(blob, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB))
        points = np.array(detections[t]["Points2D:positions"])
        camera.plot(points[:, 0], points[:, 1], "g.", markersize=4)
        ids = temporal["/camera/detections/ids"][t]
        for label, (u, v) in zip(ids["Points2D:labels"], ids["Points2D:positions"], strict=True):
            camera.annotate(label, (u, v), color="lime", fontsize=11, weight="bold")
        camera.set_title(f"camera/image and camera/detections at {t:.1f} s")
    camera.axis("off")
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=90)
    print(f"Wrote {args.out}")


if __name__ == "__main__":
    main()
