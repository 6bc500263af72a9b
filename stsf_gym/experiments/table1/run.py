"""``stsf-gym reproduce table1``: distance to a landmark by conventional fusion and by STSF.

The paper's sect. 4.2: the robot captures one landmark from six places, 7.81, 7.02, 6.28,
5.06, 5.52 and 6.32 m from it (approaching, then receding), ten frames at each. Row ``k``:
conventional fusion is motion stereo (eq. 8-20) between places ``k-1`` and ``k``; STSF fuses
the distances of every place so far, carried by odometry (eq. 2-5, eq. 3). A start place, where
the robot first captures the landmark, gives row 1 its pair. The rig is
:mod:`~stsf_gym.experiments.table1.rig`, the two measurements
:mod:`~stsf_gym.experiments.table1.measure`. Errors are over seeds (RMS, with the signed
errors' mean and spread), beside the paper's columns, the baselines the robot drove and the
stereo bound ``sqrt(2) Z^2 sigma_px / (f b)``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Annotated

import numpy as np

from stsf_gym.config_files import deep_merge, shown
from stsf_gym.envs.config import CONFIG_DIR, build, load_config, overrides_to_tree, read_yaml
from stsf_gym.episode_env import estimator_options
from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.experiments.jobs.spec import JobKind
from stsf_gym.experiments.reports import write_report
from stsf_gym.experiments.statistics import rms
from stsf_gym.experiments.table1.joint import joint_rows
from stsf_gym.experiments.table1.measure import measure_rows
from stsf_gym.experiments.table1.plot import plot_table1
from stsf_gym.experiments.table1.rig import Table1Rig
from stsf_gym.fusion import stereo_range_bound
from stsf_gym.geometry import wrap_angle
from stsf_gym.io import markdown_table
from stsf_gym.results import SCHEMA_VERSION, finite_or_none, stat
from stsf_gym.validation import ConfigError, Count, Positive, Range, require

#: Table I of the paper: world distance, conventional estimate and error, STSF estimate and error.
PAPER_TABLE1 = [
    (7.81, 8.24, 0.43, 8.24, 0.43),
    (7.02, 7.36, 0.34, 7.30, 0.28),
    (6.28, 6.53, 0.25, 6.48, 0.20),
    (5.06, 4.89, 0.17, 4.92, 0.14),
    (5.52, 5.39, 0.13, 5.63, 0.11),
    (6.32, 6.46, 0.14, 6.43, 0.11),
]


#: The rows' methods: the paper's two, STSF by GLS without and with the joint covariance.
METHODS = ("conventional", "stsf", "stsf_gls", "stsf_joint")


@dataclass(frozen=True)
class Table1Config:
    """Table I's settings (``configs/experiments/table1.yaml``), typed and ranged."""

    env: dict  # over configs/default.yaml, checked as an env config
    start_distance: Positive
    distances: tuple[Positive, ...]
    frames_per_place: Count
    speed: Positive
    approach_deg: Annotated[float, Range(gt=-90, lt=90)]  # off the board's normal
    sigma_px: Positive
    seeds: Count

    def __post_init__(self) -> None:
        require(len(self.distances) > 0, "distances", "must list at least one place")
        speed = load_config(self.env).robot.max_speed
        require(
            self.speed <= speed,
            "speed",
            f"must be at most the robot's max_speed ({speed:g} m/s), got {self.speed:g}",
        )


def load_table1_config(path: str | Path | None = None, **overrides) -> Table1Config:
    """``configs/experiments/table1.yaml`` (or ``path``) with overrides such as
    ``seeds=5`` or ``env__camera__width=800``; unknown keys and values out of range fail by
    name, naming the file (the env section is checked as an env config)."""
    path = Path(path or CONFIG_DIR / "experiments" / "table1.yaml")
    data = deep_merge(read_yaml(path), overrides_to_tree(overrides))
    try:
        return build(Table1Config, data, "table1")
    except ConfigError as err:
        raise ConfigError(err.message, err.key, shown(path)) from err


@dataclass
class SeedResult:
    """Per row (place 1..n): the truth, the baseline driven, and both methods' distances."""

    truth: list[float] = field(default_factory=list)  # true camera-to-plane distance (m)
    baseline: list[float] = field(default_factory=list)  # true distance driven from the last place
    odometry_baseline: list[float] = field(default_factory=list)  # the same by odometry
    heading_error: list[float] = field(default_factory=list)  # odometry's turn - true turn (rad)
    frames: list[int] = field(default_factory=list)  # frames with the landmark at the place
    conventional: list[float] = field(default_factory=list)  # NaN: no distance
    stsf: list[float] = field(default_factory=list)  # significance weights (eq. 4-5)
    stsf_gls: list[float] = field(default_factory=list)  # generalised least squares weights
    stsf_joint: list[float] = field(default_factory=list)  # GLS with the joint covariance


def run_seed(cfg: Table1Config, seed: int) -> SeedResult:
    """One episode of the rig, measured."""
    rig = Table1Rig(cfg.env, seed, cfg.speed, cfg.frames_per_place, cfg.approach_deg)
    places, truths = rig.capture([cfg.start_distance, *cfg.distances])
    args = (places, rig.model.camera_matrix, rig.landmark.normal, cfg.sigma_px, rig.camera_forward)
    rows = measure_rows(*args)
    joint = joint_rows(*args, rig.model.odometry_noise.calibration_cov)
    return SeedResult(
        truth=[t.distance for t in truths[1:]],
        baseline=[t.driven for t in truths[1:]],
        odometry_baseline=[float(np.hypot(*p.motion[:2])) for p in places[1:]],
        heading_error=[
            float(wrap_angle(p.motion[2] - (b.heading - a.heading)))
            for p, a, b in zip(places[1:], truths[:-1], truths[1:], strict=True)
        ],
        frames=[p.frames for p in places[1:]],
        conventional=rows["conventional"],
        stsf=rows["stsf"],
        stsf_gls=rows["stsf_gls"],
        stsf_joint=joint,
    )


def resolved_table1(cfg: Table1Config) -> dict:
    """Every value Table I runs with: its protocol, the rig's env config after all layers and
    the settings of the estimators whose code it uses."""
    return {
        "table1": cfg.__dict__,
        "env": asdict(load_config(cfg.env)),
        "estimators": {name: estimator_options(name) for name in ("odometry", "stsf")},
    }


def _run_seed(job: dict) -> SeedResult:
    return run_seed(load_table1_config(**job["config"]), job["seed"])


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
    resolved = resolved_table1(cfg)
    kind = JobKind(_run_seed, lambda job: f"seed_{job['seed']}", lambda job: resolved)
    ran = run_jobs(kind, jobs, out / "seeds.sqlite", "table1", workers=workers, unit="seed")
    results = [SeedResult(**r) for r in ran.results]
    rows = summarise(cfg, results)
    summary = {
        "schema_version": SCHEMA_VERSION,
        "config": cfg.__dict__,
        "seeds": [seed, seed + cfg.seeds - 1],
        "rows": rows,
    }
    title = "Table I reproduced: distance to a landmark, conventional fusion vs STSF"
    write_report(
        out,
        summary,
        title,
        _markdown(rows, cfg),
        markdown_name="table1.md",
        config=resolved,
        seeds=range(seed, seed + cfg.seeds),
    )
    summary["figure"] = str(plot_table1(rows, out / "table1.png"))
    return summary


def focal_length(cfg: Table1Config) -> float:
    """The camera's focal length (px) from its configured image height and field of view."""
    camera = load_config(cfg.env).camera
    return camera.height / 2 / math.tan(math.radians(camera.vfov_deg) / 2)


def summarise(cfg: Table1Config, results: list[SeedResult]) -> list[dict]:
    """One row per place: our distances and errors over seeds beside the paper's and the bound
    (for the mean baseline driven)."""
    paper = {row[0]: row for row in PAPER_TABLE1}
    rows = []
    for k, distance in enumerate(cfg.distances):
        baseline = float(np.mean([r.baseline[k] for r in results]))
        row = {
            "row": k + 1,
            "world_distance_m": distance,
            "true_distance_m": stat(r.truth[k] for r in results),
            "baseline_m": stat(r.baseline[k] for r in results),
            "odometry_baseline_m": stat(r.odometry_baseline[k] for r in results),
            "heading_error_rad": stat(r.heading_error[k] for r in results),
            "frames": stat(r.frames[k] for r in results),
        }
        for name in METHODS if all(r.stsf_joint for r in results) else METHODS[:-1]:
            estimates = [getattr(r, name)[k] for r in results]
            errors = [e - r.truth[k] for e, r in zip(estimates, results, strict=True)]
            row[f"{name}_m"] = stat(estimates)
            row[f"{name}_error_m"] = stat(errors)  # signed: mean is the bias, std the spread
            finite = [abs(e) for e in errors if math.isfinite(e)]
            row[f"{name}_rms_error_m"] = finite_or_none(rms(finite))
            row[f"{name}_median_error_m"] = float(np.median(finite)) if finite else None
        if k:  # shared errors: the same wheel calibration turns every leg's heading
            row["conventional_error_correlation"] = _correlation(
                [r.conventional[k - 1] - r.truth[k - 1] for r in results],
                [r.conventional[k] - r.truth[k] for r in results],
            )
        row["bound_m"] = float(
            stereo_range_bound(distance, focal_length(cfg), baseline, cfg.sigma_px)
        )
        if distance in paper:
            _, conv, conv_err, stsf, stsf_err = paper[distance]
            row |= {
                "paper_conventional_m": conv,
                "paper_conventional_error_m": conv_err,
                "paper_stsf_m": stsf,
                "paper_stsf_error_m": stsf_err,
            }
        rows.append(row)
    return rows


def _rms(value: dict) -> float:
    """Root mean square of a stat's values (from its mean and population std)."""
    return math.hypot(value["mean"], value["std"]) if value["mean"] is not None else math.nan


def _correlation(a: list[float], b: list[float]) -> float | None:
    """Pearson correlation over the seeds where both are finite (None: too few)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    both = np.isfinite(a) & np.isfinite(b)
    if both.sum() < 3 or np.std(a[both]) == 0 or np.std(b[both]) == 0:
        return None
    return float(np.corrcoef(a[both], b[both])[0, 1])


def _markdown(rows: list[dict], cfg: Table1Config) -> str:
    head = (
        f"{cfg.seeds} seeds; places at {', '.join(f'{d:g}' for d in cfg.distances)} m from the "
        f"board (start {cfg.start_distance:g} m), {cfg.frames_per_place} frames per place. "
        "Error: RMS over seeds (spread: std of the signed errors), median: of the absolute "
        "errors; baseline: distance driven from the previous place; bound: sqrt(2) Z^2 "
        f"sigma_px / (f b), sigma_px = {cfg.sigma_px}; odometry heading error: RMS over seeds "
        "of odometry's turn between the places less the true turn."
        "\n\n"
    )

    def error(row: dict, name: str) -> str:
        value, spread = row[f"{name}_rms_error_m"], row[f"{name}_error_m"]["std"]
        return "-" if value is None else f"{value:.3f} ({spread:.3f})"

    def median(row: dict, name: str) -> str:
        value = row[f"{name}_median_error_m"]
        return "-" if value is None else f"{value:.3f}"

    def mean(value: dict) -> str:
        return "-" if value["mean"] is None else f"{value['mean']:.2f}"

    table = [
        {
            "row": row["row"],
            "world (m)": f"{row['world_distance_m']:.2f}",
            "baseline (m)": mean(row["baseline_m"]),
            "conventional (m)": mean(row["conventional_m"]),
            "error (m)": error(row, "conventional"),
            "median": median(row, "conventional"),
            "paper conv. error (m)": row.get("paper_conventional_error_m", "-"),
            "STSF (m)": mean(row["stsf_m"]),
            "STSF error (m)": error(row, "stsf"),
            "STSF median": median(row, "stsf"),
            "paper STSF error (m)": row.get("paper_stsf_error_m", "-"),
            "STSF joint cov. error (m)": error(row, "stsf_joint") if "stsf_joint_m" in row else "-",
            "bound (m)": f"{row['bound_m']:.3f}",
            "odometry heading error (mrad)": f"{1e3 * _rms(row['heading_error_rad']):.1f}",
        }
        for row in rows
    ]
    return head + markdown_table(table)
