"""Table I's joint covariance against the seeds: is the GLS fusion's model the simulation's?

Per seed (the Table I rig, ``configs/experiments/table1.yaml``, rendered): every row's carried
distances ``t_j`` (:func:`~stsf_gym.experiments.table1.joint.joint_track`), their predicted
joint covariance and the conventional distance. Per row it prints both methods' RMS error and
predicted std, the paired difference of their squared errors (mean and standard error, and in
how many seeds the joint fusion is the better), and the carried distances' measured RMS error
and correlation beside the predicted ones. First, the wheel calibration errors the seeds drew
against the believed spread: the rows' shared error is mostly the heading that the two wheel
radii's difference puts into every leg, so a seed set that drew small differences makes every
row's error smaller and less correlated than the model predicts.

    python benchmarks/table1_joint_check.py --seeds 20
"""

from __future__ import annotations

import argparse
import multiprocessing
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from tqdm import tqdm

from stsf_gym.experiments.table1.joint import gls_distance, inverse_range, joint_track
from stsf_gym.experiments.table1.measure import measure_rows, pair_distance
from stsf_gym.experiments.table1.rig import Table1Rig
from stsf_gym.experiments.table1.run import load_table1_config


def seed_rows(seed: int) -> dict:
    """The wheel calibration errors the seed drew (``c``) and their believed covariance, and
    per row (``rows``): the truth, the conventional distance, ``t`` and its predicted
    covariance."""
    cfg = load_table1_config()
    rig = Table1Rig(cfg.env, seed, cfg.speed, cfg.frames_per_place, cfg.approach_deg)
    places, truths = rig.capture([cfg.start_distance, *cfg.distances])
    args = (rig.model.camera_matrix, rig.landmark.normal, cfg.sigma_px, rig.camera_forward)
    conventional = measure_rows(places, *args)["conventional"]
    calibration_cov = rig.model.odometry_noise.calibration_cov
    drawn = rig.env.unwrapped.encoders
    believed = drawn.calibration
    errors = np.array(
        [
            believed.wheel_radius_left / drawn.wheel_radius - 1,
            believed.wheel_radius_right / drawn.wheel_radius - 1,
            believed.wheelbase / drawn.wheelbase - 1,
        ]
    )
    rows, measured = [], []
    for k in range(1, len(places)):
        if pair_distance(places[k - 1], places[k], *args[:3]) is not None:
            measured.append(k)
        t, sigma = joint_track(places, k, measured, *args, calibration_cov)
        truth = truths[k].distance
        rows.append({"truth": truth, "conventional": conventional[k - 1], "t": t, "sigma": sigma})
    return {"calibration": errors, "calibration_cov": calibration_cov, "rows": rows}


def report_calibration(seeds: list[dict]) -> None:
    """The drawn radius difference ``c_r - c_l`` and wheelbase error, RMS over the seeds,
    as a multiple of the believed standard deviation (1 when the seeds draw as believed)."""
    drawn = np.array([s["calibration"] for s in seeds])
    cov = seeds[0]["calibration_cov"]
    difference = np.array([-1.0, 1.0, 0.0])
    print(
        f"drawn calibration ({len(seeds)} seeds), RMS / believed std: radius difference "
        f"{np.sqrt(np.mean((drawn @ difference) ** 2) / (difference @ cov @ difference)):.2f}, "
        f"wheelbase {np.sqrt(np.mean(drawn[:, 2] ** 2) / cov[2, 2]):.2f}"
    )


def report(seeds: list[list[dict]]) -> None:
    for k in range(1, len(seeds[0]) + 1):
        rows = [s[k - 1] for s in seeds if len(s[k - 1]["t"]) == k]
        if len(rows) < 3 or any(np.isnan(r["t"]).any() for r in rows):
            continue
        truth = np.array([r["truth"] for r in rows])
        conventional = np.array([r["conventional"] for r in rows]) - truth
        joint = np.array([gls_distance(r["t"], r["sigma"]) for r in rows]) - truth
        predicted_joint = []
        for r in rows:
            _, sigma_rho = inverse_range(r["t"], r["sigma"])
            ones = np.ones(k)
            predicted_joint.append(
                gls_distance(r["t"], r["sigma"]) ** 2
                / np.sqrt(ones @ np.linalg.solve(sigma_rho, ones))
            )
        errors = np.array([r["t"] for r in rows]) - truth[:, None]
        measured = errors.T @ errors / len(rows)
        predicted = np.mean([r["sigma"] for r in rows], axis=0)
        difference = joint**2 - conventional**2
        print(
            f"row {k} ({len(rows)} seeds): RMS conventional {np.sqrt(np.mean(conventional**2)):.3f}"
            f" / joint {np.sqrt(np.mean(joint**2)):.3f} m; predicted std "
            f"{np.sqrt(np.mean([r['sigma'][-1, -1] for r in rows])):.3f} / "
            f"{np.sqrt(np.mean(np.square(predicted_joint))):.3f} m; joint - conventional squared "
            f"error {difference.mean():+.3f} +- {difference.std(ddof=1) / np.sqrt(len(rows)):.3f}"
            f" m^2, joint better in {int(np.sum(np.abs(joint) < np.abs(conventional)))}"
        )
        std_m, std_p = np.sqrt(np.diag(measured)), np.sqrt(np.diag(predicted))
        print(f"  carried t: RMS {np.round(std_m, 3)} against predicted std {np.round(std_p, 3)}")
        print(f"  correlation measured\n{np.round(measured / np.outer(std_m, std_m), 2)}")
        print(f"  correlation predicted\n{np.round(predicted / np.outer(std_p, std_p), 2)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--seed0", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    seeds = range(args.seed0, args.seed0 + args.seeds)
    context = multiprocessing.get_context("forkserver")
    with ProcessPoolExecutor(args.workers, mp_context=context) as pool:
        drawn = list(tqdm(pool.map(seed_rows, seeds), total=len(seeds), desc="table1 seeds"))
    report_calibration(drawn)
    report([seed["rows"] for seed in drawn])


if __name__ == "__main__":
    main()
