"""Noise identification for the landmark estimators, on seeds the figures do not use.

Two reports, over ``--seeds`` episodes from ``--seed0`` (default 100-119; Fig. 10/11 use 0-9)
of the path follower driving on each estimator:

- ``pairs``: every motion-stereo pair measurement of the conventional estimator against the
  landmark's true pose relative to the robot, split into radial (along the ray), tangential
  and orientation errors by range, beside the model's standard deviations (pixels, slip,
  wheel calibration and mount, without the floors) and the floors of
  ``configs/estimators/conventional.yaml``. What the floors were set from.
- ``boards``: every map board's pose measurement of the smoother and MCL
  (:class:`~stsf_gym.estimators.references.measurements.LandmarkPose`: PnP pose in the robot
  frame) against the board's true pose from the robot, radial / tangential / orientation by
  range, beside the model's standard deviations without and with the floors of
  ``configs/estimators/smoother.yaml`` (``--set`` to try others), the considered camera and
  mount errors included, and the mean normalised squared error (3 dof: 3 when consistent).
  What the smoother's and MCL's board floors were set from.
- ``sonar``: every reading MCL's sonar likelihood uses (its ``sonar_beams``, those that
  echoed), its end point put at the robot's true pose, and that point's distance to the
  nearest wall in MCL's likelihood field, by range: the spread the field's ``sonar_std``
  stands for (a half-normal's ``sigma`` is the RMS of the distance), the share beyond 3 sigma
  (``sonar_random``'s readings), the correlation of the readings of one update (``N``
  readings correlated ``rho`` on average carry ``N / (1 + (N - 1) rho)`` readings' worth), and
  of one beam with itself an update later: an update that repeats the last one's error with
  correlation ``rho`` is worth ``(1 - rho) / (1 + rho)`` of an independent one, so the field's
  sigma is the per-reading spread times ``sqrt((1 + rho) / (1 - rho))``. What MCL's
  ``sonar_max_range`` and ``sonar_std`` were set from.
- ``nees``: per estimator, the 3-dof NEES, the time average of the run-averaged NEES with its
  95 % bounds (Fig. 11's judgement), its position (2-dof) and heading (1-dof) parts, RMS
  errors beside the mean model standard deviations, updates, gated measurements, and the seeds
  that needed a re-localisation or were ever more than 10 cm off. What the floors,
  ``mount_std`` and MCL's ``odometry_inflation`` were checked with.

    python benchmarks/estimator_noise.py pairs --world irl_corridor --mode fast
    python benchmarks/estimator_noise.py boards --seeds 10
    python benchmarks/estimator_noise.py sonar --seeds 10
    python benchmarks/estimator_noise.py nees --estimators odometry,conventional,stsf,ekf
    python benchmarks/estimator_noise.py nees --estimators stsf --set mount_std=0.005
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import yaml
from tqdm import tqdm

from stsf_gym.metrics import time_averaged_nees_bounds

RANGE_BINS = [(0, 2), (2, 3), (3, 4), (4, 6), (6, 9), (9, 15)]


def _env(world: str, estimator: str, mode: str, options: dict):
    from stsf_gym.agents.follower import PathFollower
    from stsf_gym.episode_env import make_episode_env
    from stsf_gym.experiments.fig10_11 import PATH_ONLY

    env = make_episode_env(world, estimator, {"camera__mode": mode}, options)
    return env, PathFollower.for_env(env, **PATH_ONLY)


def pair_errors(job: tuple) -> np.ndarray:
    """Rows: range, radial, tangential and orientation error, and the model's variances
    (radial, tangential, orientation) with their floors, for each pair measurement."""
    from stsf_gym.estimators.landmark_fusion import LandmarkFusionEstimator
    from stsf_gym.estimators.landmark_observation import landmark_world_pose
    from stsf_gym.geometry import compose, inverse

    world, seed, mode, options = job
    env, follower = _env(world, "conventional", mode, options)
    estimator, measured, rows = env.get_wrapper_attr("estimator"), [], []
    pair_measurement = LandmarkFusionEstimator._pair_measurement

    def recorded(self, previous, current):
        out = pair_measurement(self, previous, current)
        if out is not None:
            measured.append((current.landmark, *out))
        return out

    LandmarkFusionEstimator._pair_measurement = recorded
    obs, info, done = *env.reset(seed=seed), False
    while not done:
        obs, _, terminated, truncated, info = env.step(follower.act(obs["pose"], obs["sonar"]))
        done = terminated or truncated
        for landmark, z, cov, by_calibration in measured:
            # the considered errors too: the wheel calibration through the baseline, the mount
            calibration_cov = estimator.model.odometry_noise.calibration_cov
            cov = cov + by_calibration @ calibration_cov @ by_calibration.T
            cov = cov + np.diag([estimator.mount_std**2] * 2 + [0.0])
            truth = compose(inverse(info["true_pose"]), landmark_world_pose(landmark))
            error = z - truth
            error[2] = math.remainder(error[2], math.tau)
            bearing = math.atan2(truth[1], truth[0])
            c, s = math.cos(bearing), math.sin(bearing)
            to_ray = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
            along, model = to_ray @ error, to_ray @ cov @ to_ray.T
            floor = estimator.position_std_floor + estimator.position_std_per_m * math.hypot(*z[:2])
            rows.append(
                [
                    math.hypot(*truth[:2]),
                    *along,
                    *np.diag(model),
                    floor**2,
                    estimator.orientation_var_floor,
                ]
            )
        measured.clear()
    env.close()
    return np.array(rows).reshape(-1, 9)


def board_errors(job: tuple) -> np.ndarray:
    """Rows: range, radial, tangential and orientation error, the model's variances without
    the floors (radial, tangential, orientation) and the normalised squared error with them,
    for each board the smoother measures."""
    from stsf_gym.estimators.references import smoother as smoother_module
    from stsf_gym.geometry import compose, inverse

    world, seed, mode, options = job
    env, follower = _env(world, "smoother", mode, options)
    estimator, measured, rows = env.get_wrapper_attr("estimator"), [], []
    landmark_pose = smoother_module.landmark_pose

    def recorded(observation, *floors):
        out = landmark_pose(observation, *floors)
        measured.append((observation.cov, out))
        return out

    smoother_module.landmark_pose = recorded
    obs, info, done = *env.reset(seed=seed), False
    k_cov = estimator.k_cov  # the considered errors' prior (camera, mount, wheels)
    while not done:
        obs, _, terminated, truncated, info = env.step(follower.act(obs["pose"], obs["sonar"]))
        done = terminated or truncated
        for pnp_cov, board in measured:
            considered = board.by_considered @ k_cov @ board.by_considered.T
            truth = compose(inverse(info["true_pose"]), board.landmark_pose)
            error = board.z - truth
            error[2] = math.remainder(error[2], math.tau)
            bearing = math.atan2(truth[1], truth[0])
            c, s = math.cos(bearing), math.sin(bearing)
            to_ray = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
            model = to_ray @ (pnp_cov + considered) @ to_ray.T
            d2 = error @ np.linalg.solve(board.noise + considered, error)
            rows.append([math.hypot(*truth[:2]), *(to_ray @ error), *np.diag(model), d2])
        measured.clear()
    smoother_module.landmark_pose = landmark_pose
    env.close()
    return np.array(rows).reshape(-1, 8)


def sonar_distances(job: tuple) -> np.ndarray:
    """Rows, one per MCL sonar update step: each used reading's range and its end point's
    distance to the nearest wall at the true pose (NaN where it did not echo)."""
    world, seed, mode, options = job
    env, follower = _env(world, "mcl", mode, options)
    obs, info, done, rows = *env.reset(seed=seed), False, []
    mcl = env.get_wrapper_attr("estimator")
    max_range = mcl.model.sonar.max_range
    while not done:
        obs, _, terminated, truncated, info = env.step(follower.act(obs["pose"], obs["sonar"]))
        done = terminated or truncated
        ranges = np.asarray(obs["sonar"], dtype=float)
        used = mcl.used_beams(len(ranges))
        ends = mcl.end_points(np.asarray(info["true_pose"], float)[None], ranges, used)[0]
        r = ranges[used]
        distance = np.where(r < max_range - 1e-6, mcl.field.distance(ends), np.nan)
        rows.append([*r, *distance])
    env.close()
    return np.array(rows)


def report_sonar(runs: list[np.ndarray]) -> None:
    beams = runs[0].shape[1] // 2
    rows = np.concatenate(runs)
    rng, distance = rows[:, :beams].ravel(), rows[:, beams:].ravel()
    echoed = ~np.isnan(distance)
    rng, distance = rng[echoed], distance[echoed]
    sigma = math.sqrt(np.mean(distance**2))
    for _ in range(20):  # the half-normal's sigma without the readings beyond 3 sigma
        sigma = math.sqrt(np.mean(distance[distance < 3 * sigma] ** 2))
    beyond = float(np.mean(distance >= 3 * sigma))
    print(
        f"{len(distance)} echoed readings of {beams} used beams; distance to the nearest wall "
        f"at the true pose: RMS {math.sqrt(np.mean(distance**2)):.3f} m, sigma without the "
        f"readings beyond 3 sigma {sigma:.3f} m, share beyond {beyond:.3f}"
    )
    print("| range (m) | n | RMS distance (m) | sigma within 3 sigma (m) |")
    print("|---|---|---|---|")
    for low, high, m, rms in _range_bins(rng):
        d = distance[m]
        print(
            f"| {low}-{high} | {m.sum()} | {rms(distance):.3f} | "
            f"{math.sqrt(np.mean(d[d < 3 * sigma] ** 2)):.3f} |"
        )
    # correlation of the distances of one update's readings, over the steps where all echoed
    d = rows[:, beams:]
    full = d[~np.isnan(d).any(axis=1)]
    rho = np.corrcoef(full.T)
    mean_rho = float(rho[~np.eye(beams, dtype=bool)].mean())
    print(
        f"mean correlation between the {beams} readings of an update ({len(full)} steps all "
        f"echoed): {mean_rho:.2f}; worth {beams / (1 + (beams - 1) * mean_rho):.1f} independent"
    )
    # correlation of one beam's distance with itself an update later (readings under NEAR_M)
    for lag in SONAR_LAGS:
        rho = np.nanmean(
            [
                _lag_correlation(run[:, beams + b], run[:, b], lag)
                for run in runs
                for b in range(beams)
            ]
        )
        print(
            f"one beam's distance {lag} steps ({lag * STEP_S:.1f} s) later: correlation "
            f"{rho:.2f}; an update repeating it is worth {(1 - rho) / (1 + rho):.2f} of a new "
            f"one, so the field's sigma for independent updates is "
            f"{sigma_near(rows, beams) * math.sqrt((1 + rho) / (1 - rho)):.3f} m"
        )


#: lags (control steps of 0.1 s) of the sonar report's autocorrelation; at 0.122 m/s MCL
#: updates every 0.1 m driven, about 8 steps
SONAR_LAGS = (1, 8, 40)
STEP_S = 0.1
NEAR_M = 2.0  # m: the readings the correlation and the near spread are taken over


def _lag_correlation(distance: np.ndarray, ranges: np.ndarray, lag: int) -> float:
    """Correlation of ``distance`` with itself ``lag`` steps later, readings under NEAR_M."""
    near = ~np.isnan(distance) & (ranges < NEAR_M)
    both = near[:-lag] & near[lag:]
    if both.sum() < 50:
        return float("nan")
    return float(np.corrcoef(distance[:-lag][both], distance[lag:][both])[0, 1])


def sigma_near(rows: np.ndarray, beams: int) -> float:
    """RMS end-point distance of the echoed readings under NEAR_M."""
    ranges, distance = rows[:, :beams].ravel(), rows[:, beams:].ravel()
    near = ~np.isnan(distance) & (ranges < NEAR_M)
    return math.sqrt(np.mean(distance[near] ** 2))


def nees_parts(job: tuple) -> dict:
    """NEES parts, squared errors and model variances at every step of one episode."""
    world, seed, mode, options, estimator_name = job
    env, follower = _env(world, estimator_name, mode, options)
    obs, info, done, rows = *env.reset(seed=seed), False, []
    while not done:
        obs, _, terminated, truncated, info = env.step(follower.act(obs["pose"], obs["sonar"]))
        done = terminated or truncated
        error = obs["pose"].astype(float) - info["true_pose"]
        error[2] = math.remainder(error[2], math.tau)
        cov = obs["pose_cov"].reshape(3, 3).astype(float)
        nees = error @ np.linalg.solve(cov, error)
        position = error[:2] @ np.linalg.solve(cov[:2, :2], error[:2])
        rows.append([nees, position, error[2] ** 2 / cov[2, 2], *(error**2), *np.diag(cov)])
    counters = dict(env.get_wrapper_attr("estimator").counters)
    env.close()
    rows = np.array(rows)
    return {
        "estimator": estimator_name,
        "seed": seed,
        "rows": rows,
        "counters": counters,
        "bad": bool(counters.get("relocalised") or np.sqrt(rows[:, 3] + rows[:, 4]).max() > 0.1),
    }


def _map(function, jobs: list, workers: int) -> list:
    context = multiprocessing.get_context("forkserver")
    with ProcessPoolExecutor(workers, mp_context=context) as pool:
        return list(tqdm(pool.map(function, jobs), total=len(jobs), desc=function.__name__))


def _range_bins(rng: np.ndarray):
    """``(low, high, mask, rms)`` of every range bin holding at least 5 measurements; ``rms(x)``
    is the RMS of ``x`` inside the bin."""
    for low, high in RANGE_BINS:
        m = (rng >= low) & (rng < high)
        if m.sum() >= 5:
            yield low, high, m, lambda x, m=m: math.sqrt(np.mean(x[m] ** 2))


def report_pairs(rows: np.ndarray) -> None:
    rng, radial, tangential, orientation, var_r, var_t, var_o, floor_p, floor_o = rows.T
    print(f"{len(rows)} pair measurements")
    print(
        "| range (m) | n | radial RMS / model / floor (cm) | tangential RMS / model (cm) | "
        "orientation RMS / model / floor (deg) |"
    )
    print("|---|---|---|---|---|")
    for low, high, m, rms in _range_bins(rng):

        def model(var, floor, m=m):
            return math.sqrt(np.mean(var[m] - floor[m]))

        print(
            f"| {low}-{high} | {m.sum()} | {100 * rms(radial):.2f} / "
            f"{100 * model(var_r, floor_p):.2f} / {100 * math.sqrt(floor_p[m].mean()):.2f} | "
            f"{100 * rms(tangential):.2f} / {100 * model(var_t, floor_p):.2f} | "
            f"{math.degrees(rms(orientation)):.2f} / {math.degrees(model(var_o, floor_o)):.2f} / "
            f"{math.degrees(math.sqrt(floor_o[m].mean())):.2f} |"
        )


def report_boards(rows: np.ndarray) -> None:
    rng, radial, tangential, orientation, var_r, var_t, var_o, d2 = rows.T
    print(f"{len(rows)} board measurements; normalised squared error (3 dof) {d2.mean():.2f}")
    print(
        "| range (m) | n | radial RMS / model (cm) | tangential RMS / model (cm) | "
        "orientation RMS / model (deg) | normalised (3) |"
    )
    print("|---|---|---|---|---|---|")
    for low, high, m, rms in _range_bins(rng):
        print(
            f"| {low}-{high} | {m.sum()} | {100 * rms(radial):.2f} / "
            f"{100 * math.sqrt(var_r[m].mean()):.2f} | {100 * rms(tangential):.2f} / "
            f"{100 * math.sqrt(var_t[m].mean()):.2f} | {math.degrees(rms(orientation)):.2f} / "
            f"{math.degrees(math.sqrt(var_o[m].mean())):.2f} | {d2[m].mean():.2f} |"
        )


def report_nees(results: list[dict], estimators: list[str]) -> None:
    print(
        "| estimator | NEES (3) | its time average (95 % bounds) | position (2) | heading (1) | "
        "RMS x / std (cm) | "
        "RMS y / std (cm) | RMS heading / std (deg) | updates | gated | off or re-localised |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in estimators:
        runs = [r for r in results if r["estimator"] == name]
        rows = np.concatenate([r["rows"] for r in runs])
        mean = rows.mean(axis=0)
        bad = [r["seed"] for r in runs if r["bad"]]
        length = min(len(r["rows"]) for r in runs)
        trace = np.mean([r["rows"][:length, 0] for r in runs], axis=0)
        average, (low, high), _ = time_averaged_nees_bounds(trace, 3, len(runs))

        def counter(key, runs=runs):
            return np.mean([r["counters"].get(key, 0) for r in runs])

        print(
            f"| {name} | {mean[0]:.2f} | {average:.2f} ({low:.2f}-{high:.2f}) | {mean[1]:.2f} | "
            f"{mean[2]:.2f} | "
            f"{100 * math.sqrt(mean[3]):.2f} / {100 * math.sqrt(mean[6]):.2f} | "
            f"{100 * math.sqrt(mean[4]):.2f} / {100 * math.sqrt(mean[7]):.2f} | "
            f"{math.degrees(math.sqrt(mean[5])):.2f} / {math.degrees(math.sqrt(mean[8])):.2f} | "
            f"{counter('landmark_updates'):.0f} | {counter('gated_out'):.1f} | "
            f"{len(bad)} {bad} |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("report", choices=["pairs", "boards", "sonar", "nees"])
    parser.add_argument("--world", default="irl_corridor")
    parser.add_argument("--mode", default="fast", choices=["fast", "rendered"])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--seed0", type=int, default=100)
    parser.add_argument("--estimators", default="conventional,stsf,ekf")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="estimator option for every estimator, e.g. mount_std=0.005",
    )
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    options = {}
    for item in args.set:
        key, sep, value = item.partition("=")
        if not sep:
            parser.error(f"--set needs KEY=VALUE, got {item!r}")
        options[key] = yaml.safe_load(value)
    seeds = range(args.seed0, args.seed0 + args.seeds)
    if args.report in ("pairs", "boards", "sonar"):
        jobs = [(args.world, seed, args.mode, options) for seed in seeds]
        if args.report == "pairs":
            report_pairs(np.concatenate(_map(pair_errors, jobs, args.workers)))
        elif args.report == "sonar":
            report_sonar(_map(sonar_distances, jobs, args.workers))
        else:
            report_boards(np.concatenate(_map(board_errors, jobs, args.workers)))
    else:
        estimators = args.estimators.split(",")
        jobs = [(args.world, s, args.mode, options, e) for e in estimators for s in seeds]
        report_nees(_map(nees_parts, jobs, args.workers), estimators)


if __name__ == "__main__":
    main()
