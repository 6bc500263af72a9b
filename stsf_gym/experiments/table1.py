"""``stsf-gym reproduce table1``: distance to a landmark by conventional fusion and by STSF.

The paper's sect. 4.2: one landmark seen from six places at 7.81, 7.02, 6.28, 5.06, 5.52 and
6.32 m, ten frames per place. Here the robot sweeps sideways past the landmark at each
distance, one frame a second at 12.2 cm/s, the camera panned onto the landmark from the
odometry heading. For each pair of consecutive frames the detector's square centres give the
plane distance ``D`` by motion stereo (eq. 8-20), with the camera motion from odometry: the
estimators' dead reckoning (:class:`~stsf_gym.estimators.dead_reckoning.OdometryEstimator`,
its covariance with the wheel calibration errors fixed per run).

- Conventional fusion: ``D`` from the current two frames only.
- STSF: every pair measured so far, carried into the current frame by odometry (eq. 3,
  propagating its uncertainty) and fused (eq. 2) in inverse range with the significance
  weights of eq. 4-5; the same fused with generalised-least-squares weights for comparison.

A row's conventional error is over all pairs of that place; its STSF error is that of the
estimate at the place's last frame. Errors are RMS over seeds, with the spread (std) beside,
next to the paper's numbers and the bound ``sqrt(2) Z^2 sigma_px / (f b)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import gymnasium as gym
import numpy as np

import stsf_gym  # noqa: F401 - registers the env ids
from envs.config import CONFIG_DIR, build, deep_merge, load_config, overrides_to_tree, read_yaml
from stsf_gym.estimators import SensorModel, make_estimator
from stsf_gym.estimators.dead_reckoning import OdometryEstimator
from stsf_gym.estimators.pair_range import pair_range
from stsf_gym.experiments.cache import run_cached
from stsf_gym.experiments.plots import pyplot
from stsf_gym.experiments.reports import write_report
from stsf_gym.experiments.statistics import rms
from stsf_gym.fusion import (
    stereo_range_bound,
    stsf_fuse,
    to_inverse_range,
    transform_range_track,
)
from stsf_gym.geometry import to_se3, wrap_angle
from stsf_gym.io import markdown_table, save_figure
from stsf_gym.vision.detector import LandmarkDetector
from stsf_gym.wrappers import sensor_model

#: Table I of the paper: world distance, conventional estimate and error, STSF estimate and error.
PAPER_TABLE1 = [
    (7.81, 8.24, 0.43, 8.24, 0.43),
    (7.02, 7.36, 0.34, 7.30, 0.28),
    (6.28, 6.53, 0.25, 6.48, 0.20),
    (5.06, 4.89, 0.17, 4.92, 0.14),
    (5.52, 5.39, 0.13, 5.63, 0.11),
    (6.32, 6.46, 0.14, 6.43, 0.11),
]


@dataclass(frozen=True)
class Table1Config:
    env: dict
    distances: tuple[float, ...]
    frames_per_location: int
    sweep_speed: float
    sweep_start: float
    turn_rate: float
    sigma_px: float
    seeds: int


def load_table1_config(path: str | Path | None = None, **overrides) -> Table1Config:
    """``configs/experiments/table1.yaml`` (or ``path``) with overrides such as
    ``seeds=5`` or ``env__camera__width=800``; unknown keys fail by name."""
    data = read_yaml(path or CONFIG_DIR / "experiments" / "table1.yaml")
    return build(Table1Config, deep_merge(data, overrides_to_tree(overrides)), "table1")


def dead_reckoning(model: SensorModel, pose: np.ndarray) -> OdometryEstimator:
    """The estimators' odometry from ``pose`` with no uncertainty yet: restarted at the origin,
    it gives the motion since then and its covariance."""
    odometry = make_estimator("odometry")
    odometry.reset(model, pose, np.zeros((3, 3)))
    return odometry


def restart_at_origin(odometry: OdometryEstimator) -> None:
    """Measure the motion from here on: the origin, with no uncertainty."""
    odometry.restart(np.zeros(3), np.zeros((3, 3)))


@dataclass
class _Frame:
    location: int
    points: dict[int, np.ndarray]  # square index -> pixel
    world_from_camera: np.ndarray  # believed: odometry pose and mount kinematics
    heading: float  # odometry heading
    motion_cov: np.ndarray  # odometry covariance of the motion since the previous frame


@dataclass
class SeedResult:
    """Per frame: place index, true distance, conventional and STSF estimates (NaN: none)."""

    location: list[int] = field(default_factory=list)
    truth: list[float] = field(default_factory=list)
    conventional: list[float] = field(default_factory=list)
    stsf: list[float] = field(default_factory=list)  # significance weights (eq. 4-5)
    stsf_gls: list[float] = field(default_factory=list)  # generalised least squares weights


class Table1Run:
    """One seeded run of the experiment in its own env."""

    def __init__(self, cfg: Table1Config, seed: int) -> None:
        self.cfg, self.seed = cfg, seed
        self.env = gym.make("stsf_gym/Corridor-v0", config=cfg.env)
        u = self.env.unwrapped
        self.robot_cfg = u.config.robot
        self.landmark = u.landmarks[0]
        self.K = u.camera_matrix
        self.detector = LandmarkDetector(u.config.world.landmark_pattern)
        self.result = SeedResult()
        self.frames: list[_Frame] = []
        self.track: list[tuple[float, float]] = []  # (D, var) per measurement
        self.steps: list[tuple[float, float]] = []  # (change of D, var) between measurements

    # --- driving the rig (on the true pose: the experimenter places the robot) ---------------
    def run(self) -> SeedResult:
        cfg = self.cfg
        start = [cfg.distances[0], -cfg.sweep_start, math.pi / 2]
        _, self.info = self.env.reset(seed=self.seed, options={"start_pose": start})
        model = sensor_model(self.env)
        self.odometry = dead_reckoning(model, self.info["true_pose"])  # from the true start
        self.since_frame = dead_reckoning(model, np.zeros(3))
        self.since_measurement = dead_reckoning(model, np.zeros(3))
        try:
            for i, distance in enumerate(cfg.distances):
                direction = 1.0 if i % 2 == 0 else -1.0
                if i:
                    self._turn(0.0 if distance > self.info["true_pose"][0] else math.pi)
                    self._drive_to_x(distance)
                self._turn(direction * math.pi / 2)
                self._sweep(i, direction)
        finally:
            self.env.close()
        return self.result

    def _act(self, v: float, w: float, location: int | None = None) -> None:
        """One env step; the camera pans onto the landmark from the odometry pose."""
        x, y, yaw = self.odometry.mean
        camera_xy = np.array([x, y]) + self.robot_cfg.camera_forward * np.array(
            [math.cos(yaw), math.sin(yaw)]
        )
        to_landmark = self.landmark.centre[:2] - camera_xy
        pan = wrap_angle(math.atan2(to_landmark[1], to_landmark[0]) - yaw)
        scale = (
            self.robot_cfg.max_speed,
            self.robot_cfg.max_yaw_rate,
            math.radians(self.robot_cfg.pan_limit_deg),
        )
        action = np.clip(np.array([v, w, pan]) / scale, -1, 1).astype(np.float32)
        obs, _, terminated, truncated, self.info = self.env.step(action)
        if terminated or truncated:
            raise RuntimeError(f"table1 rig stopped early (collision: {self.info['collision']})")
        for odometry in (self.odometry, self.since_frame, self.since_measurement):
            odometry.predict(obs)
        if location is not None and obs["image_new"]:
            self._frame(obs, location)

    def _turn(self, heading: float) -> None:
        while abs(err := wrap_angle(heading - self.info["true_pose"][2])) > 0.01:
            self._act(0.0, float(np.clip(2.0 * err, -self.cfg.turn_rate, self.cfg.turn_rate)))

    def _drive_to_x(self, x: float) -> None:
        heading = self.info["true_pose"][2]
        sign = math.cos(heading)
        while (x - self.info["true_pose"][0]) * sign > 0.005:
            v = min(self.cfg.sweep_speed, 0.5 * abs(x - self.info["true_pose"][0]) + 0.02)
            self._act(v, -2.0 * wrap_angle(self.info["true_pose"][2] - heading))

    def _sweep(self, location: int, direction: float) -> None:
        heading = direction * math.pi / 2
        restart_at_origin(self.since_frame)
        count = len(self.frames)
        while len(self.frames) - count < self.cfg.frames_per_location:
            steer = -2.0 * wrap_angle(self.info["true_pose"][2] - heading)
            self._act(self.cfg.sweep_speed, steer, location)

    # --- measuring ----------------------------------------------------------------------------
    def _frame(self, obs: dict, location: int) -> None:
        pan, tilt = obs["camera_pan_tilt"]
        robot_from_camera = self.env.unwrapped.robot_from_camera(pan, tilt)
        pose = self.odometry.mean
        frame = _Frame(
            location,
            self._detect(obs["image"]),
            to_se3(pose) @ robot_from_camera,
            float(pose[2]),
            self.since_frame.cov.copy(),
        )
        restart_at_origin(self.since_frame)
        previous = self.frames[-1] if self.frames else None
        self.frames.append(frame)
        camera = self.info["camera_pose"][:3, 3]
        truth = float(np.dot(self.landmark.normal, camera - self.landmark.centre))
        conventional, stsf = math.nan, {"significance": math.nan, "gls": math.nan}
        if previous is not None and previous.location == location:
            measured = self._motion_stereo(previous, frame)
            if measured is not None:
                conventional = measured[0]
                stsf = self._stsf(frame, *measured)
        for column, value in (
            ("location", location),
            ("truth", truth),
            ("conventional", conventional),
            ("stsf", stsf["significance"]),
            ("stsf_gls", stsf["gls"]),
        ):
            getattr(self.result, column).append(value)

    def _detect(self, image: np.ndarray) -> dict[int, np.ndarray]:
        for detection in self.detector.detect(image):
            if detection.landmark_id == self.landmark.id:
                return dict(zip(detection.indices.tolist(), detection.image_points, strict=True))
        return {}

    def _motion_stereo(self, a: _Frame, b: _Frame) -> tuple[float, float] | None:
        """``D`` and its variance from frames ``a`` (k-1) and ``b`` (k), eq. 8-20."""
        world_from_camera = b.world_from_camera[:3, :3]
        return pair_range(
            a.points,
            b.points,
            self.K,
            np.linalg.inv(a.world_from_camera) @ b.world_from_camera,
            world_from_camera.T @ -self.landmark.normal,  # towards the plane, camera k
            b.motion_cov,
            world_from_camera.T @ to_se3(np.array([0, 0, b.heading]))[:3, :3],
            self.cfg.sigma_px,
        )

    def _stsf(self, frame: _Frame, D: float, var: float) -> dict[str, float]:
        """Eq. 2-5 over every measurement so far, carried into this frame by odometry (eq. 3)
        and fused in inverse range, with the paper's significance weights and with GLS."""
        if self.track:
            self.steps.append(self._range_step(self.last_heading))
        self.track.append((D, var))
        self.last_heading = frame.heading
        restart_at_origin(self.since_measurement)
        ranges, variances = zip(*self.track, strict=True)
        steps, step_variances = zip(*self.steps, strict=True) if self.steps else ((), ())
        rho, cov = to_inverse_range(
            *transform_range_track(ranges, variances, steps, step_variances)
        )
        return {
            method: 1.0 / float(stsf_fuse(rho, cov, method=method).x[0])
            for method in ("significance", "gls")
        }

    def _range_step(self, heading: float) -> tuple[float, float]:
        """Change of the plane distance since the last measurement, from odometry, and its
        variance: ``n . (camera now - camera then)`` with the motion ``u`` in that frame."""
        u, Q = self.since_measurement.mean, self.since_measurement.cov
        normal = to_se3(np.array([0, 0, heading]))[:2, :2].T @ self.landmark.normal[:2]
        c = self.robot_cfg.camera_forward
        moved = u[:2] + c * np.array([math.cos(u[2]), math.sin(u[2])]) - (c, 0.0)
        gradient = np.array(
            [normal[0], normal[1], c * (normal[1] * math.cos(u[2]) - normal[0] * math.sin(u[2]))]
        )
        return float(normal @ moved), float(gradient @ Q @ gradient)


# --- many seeds, the table, the figure ---------------------------------------------------------
def _run_seed(job: dict) -> SeedResult:
    return Table1Run(load_table1_config(**job["config"]), job["seed"]).run()


def run_table1(
    out: str | Path, seed: int = 0, config: str | Path | None = None, workers: int = 1, **overrides
) -> dict:
    """Run ``cfg.seeds`` seeds from ``seed``; write results.json, table1.md and table1.png.

    Each seed's result is saved in ``out/seeds/`` as it finishes and reused by a rerun with
    the same config, so an interrupted run loses nothing.
    """
    cfg = load_table1_config(config, **overrides)
    out = Path(out)
    jobs = [{"config": cfg.__dict__, "seed": s} for s in range(seed, seed + cfg.seeds)]
    results = [
        SeedResult(**r)
        for r in run_cached(
            _run_seed,
            jobs,
            out / "seeds",
            lambda job: f"seed_{job['seed']}",
            workers,
            "table1 seeds",
        )
    ]
    rows = summarise(cfg, results)
    summary = {"config": cfg.__dict__, "seeds": [seed, seed + cfg.seeds - 1], "rows": rows}
    title = "Table I reproduced: distance to a landmark, conventional fusion vs STSF"
    write_report(out, summary, title, _markdown(rows, cfg), markdown_name="table1.md")
    summary["figure"] = str(_plot(cfg, results, out / "table1.png"))
    return summary


def summarise(cfg: Table1Config, results: list[SeedResult]) -> list[dict]:
    """One row per place: our estimates and errors beside the paper's and the bound."""
    env_cfg = load_config(cfg.env)
    focal = env_cfg.camera.height / 2 / math.tan(math.radians(env_cfg.camera.vfov_deg) / 2)
    baseline = cfg.sweep_speed / env_cfg.camera.rate_hz
    paper = {row[0]: row for row in PAPER_TABLE1}
    rows = []
    for i, distance in enumerate(cfg.distances):
        conv_err, conv_est, stsf_err, stsf_est, gls_err = [], [], [], [], []
        for r in results:
            at = [k for k, loc in enumerate(r.location) if loc == i]
            pairs = [k for k in at if not math.isnan(r.conventional[k])]
            conv_err += [r.conventional[k] - r.truth[k] for k in pairs]
            conv_est += [r.conventional[k] for k in pairs]
            last = pairs[-1:]
            stsf_err += [r.stsf[k] - r.truth[k] for k in last]
            stsf_est += [r.stsf[k] for k in last]
            gls_err += [r.stsf_gls[k] - r.truth[k] for k in last]
        rows.append(
            {
                "row": i + 1,
                "world (m)": distance,
                "conventional (m)": float(np.mean(conv_est)) if conv_est else math.nan,
                "conventional error (m)": rms(conv_err),
                "conventional spread (m)": float(np.std(np.abs(conv_err)))
                if conv_err
                else math.nan,
                "STSF (m)": float(np.mean(stsf_est)) if stsf_est else math.nan,
                "STSF error (m)": rms(stsf_err),
                "STSF spread (m)": float(np.std(np.abs(stsf_err))) if stsf_err else math.nan,
                "STSF-GLS error (m)": rms(gls_err),
                "bound (m)": float(stereo_range_bound(distance, focal, baseline, cfg.sigma_px)),
                "paper conventional error (m)": paper[distance][2] if distance in paper else "-",
                "paper STSF error (m)": paper[distance][4] if distance in paper else "-",
                "pairs": len(conv_err),
            }
        )
    return rows


def _markdown(rows: list[dict], cfg: Table1Config) -> str:
    head = (
        f"{cfg.seeds} seeds, {cfg.frames_per_location} frames per place, baseline "
        f"{cfg.sweep_speed * 100:.1f} cm between frames. Errors are "
        "RMS over seeds (conventional: over every pair at the place; STSF: at its last frame); "
        f"bound: sqrt(2) Z^2 sigma_px / (f b) with sigma_px = {cfg.sigma_px}.\n\n"
    )
    return head + markdown_table(rows)


def _plot(cfg: Table1Config, results: list[SeedResult], path: Path) -> Path:
    plt = pyplot()
    n = min(len(r.truth) for r in results)
    truth = np.array([r.truth[:n] for r in results])
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for name, label, color in (
        ("conventional", "conventional", "tab:orange"),
        ("stsf", "STSF (significance)", "tab:blue"),
        ("stsf_gls", "STSF (GLS)", "tab:green"),
    ):
        errors = np.abs(np.array([getattr(r, name)[:n] for r in results]) - truth)
        rms = np.sqrt(np.nanmean(errors**2, axis=0))
        ax.plot(np.arange(1, n + 1), rms, "o-", ms=3, color=color, label=f"{label}, RMS error")
    location = np.array(results[0].location[:n])
    for i in range(1, len(cfg.distances)):
        ax.axvline(np.argmax(location == i) + 0.5, color="0.8", lw=1)
    ax.set_xlabel("frame")
    ax.set_ylabel("distance error (m)")
    ax.set_title(
        f"Table I: error vs frame over {len(results)} seeds "
        f"(places at {', '.join(f'{d:g}' for d in cfg.distances)} m)"
    )
    ax.legend()
    try:
        return save_figure(fig, path)
    finally:
        plt.close(fig)
