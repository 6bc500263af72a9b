"""``stsf-gym train``: a learnt agent on one pose source, seed by seed, or a campaign (one run
per pose source and seed, ``--estimators``) on the local or Ray backend."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tqdm import tqdm

from stsf_gym.agents.training.hyperparams import METHODS
from stsf_gym.agents.training.preflight import check_runs, check_seeds
from stsf_gym.agents.training.train import train
from stsf_gym.cli import inputs, options
from stsf_gym.config import parse_overrides
from stsf_gym.envs.suite import suite_names
from stsf_gym.experiments.campaign import campaign_jobs, run_campaign
from stsf_gym.experiments.jobs.train_estimate import plan, record_run
from stsf_gym.validation import ConfigError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``train``."""
    options.common(
        parser, "out/train", "hyper-parameter YAML (default configs/agents/<learner>.yaml)"
    )
    parser.add_argument(
        "--algo",
        choices=list(METHODS),
        default="ppo",
        help="dagger: cloning + DAgger rounds; dagger+ppo: then PPO on the reward; ppo, sac: "
        "reward (ppo: after the demonstrations if the settings enable them) (ppo)",
    )
    parser.add_argument(
        "--estimator", help=f"pose source the agent drives on ({options.DEFAULT_POSE_SOURCE})"
    )
    parser.add_argument(
        "--estimators",
        help="a campaign: one run per pose source (comma-separated) and seed, each in "
        "OUT/<pose source>/seed-<s>/; a rerun resumes where it stopped",
    )
    parser.add_argument(
        "--timesteps",
        type=options.whole,
        help="the reward stage's budget in the policy's steps, summed over the envs: decisions "
        "(0.5 s each) with --suite, control steps (0.1 s) otherwise (default: the "
        "hyper-parameter file's)",
    )
    parser.add_argument("--n-envs", type=options.whole, help="parallel envs (hyper-parameter file)")
    parser.add_argument(
        "--seeds",
        type=options.whole,
        default=1,
        help="training seeds SEED.. (1); each in OUT/seed-<s>/",
    )
    options.world(parser)
    options.backend(parser, "a campaign's runs at once on a local Ray (2; locally one at a time)")
    parser.add_argument(
        "--suite",
        choices=suite_names(),
        help="train on a benchmark suite's train worlds and task, evaluate on its val worlds",
    )


def run(args: argparse.Namespace) -> dict:
    """Train every run (skipping those finished); print a line per run."""
    world = inputs.world(args)
    if args.seeds < 1:
        raise ConfigError(f"--seeds must be at least 1, got {args.seeds}")
    if args.estimators is not None and args.estimator is not None:
        raise ConfigError(
            "--estimator names one run's pose source, --estimators a campaign's: give one"
        )
    shared = {
        "algo": args.algo,
        "timesteps": args.timesteps,
        "world": world,
        "config": args.config,
        "overrides": parse_overrides(args.overrides),
        "n_envs": args.n_envs,
        "suite": args.suite,
    }
    seeds = range(args.seed, args.seed + args.seeds)
    if args.estimators is not None:  # the cross product: OUT/<pose source>/seed-<s>/
        jobs = campaign_jobs(shared, args.out, inputs.pose_sources(args.estimators), seeds)
    else:
        estimator = args.estimator or options.DEFAULT_POSE_SOURCE
        one = args.seeds == 1
        jobs = [
            {**shared, "estimator": estimator, "seed": s, "out": _seed_folder(args.out, s, one)}
            for s in seeds
        ]
    check_seeds(args.seed, args.seeds)
    check_runs(jobs)
    if args.estimators is not None:
        return _campaign(args, jobs)
    if args.backend != "local" or args.address is not None:
        raise ConfigError("--backend and --address are for a campaign (--estimators)")
    said, lefts = plan(jobs, 1)
    print(said, file=sys.stderr)
    runs = []
    for job, left in zip(jobs, lefts, strict=True):
        try:
            summary = train(**job, progress_bar=not args.json)
        except KeyboardInterrupt:
            print(
                f"interrupted: rerun the same command to resume from the last round or update "
                f"saved in {job['out']}",
                file=sys.stderr,
            )
            raise SystemExit(130) from None
        runs.append(summary)
        record_run(job, left, summary)
        if not args.json:
            print(run_line(job["estimator"], job["seed"], summary, job["out"]))
    return runs[0] if len(runs) == 1 else {"runs": runs}


def _seed_folder(out: Path, seed: int, only: bool) -> Path:
    """A run's folder: ``out`` itself for the only seed, else ``out/seed-<seed>``."""
    return out if only else out / f"seed-{seed}"


def _campaign(args: argparse.Namespace, jobs: list[dict]) -> dict:
    """``train --estimators``: every (pose source, seed) run, skipped when finished, on the
    backend asked for (:mod:`stsf_gym.experiments.campaign`)."""
    if args.workers < 1:
        raise ConfigError(f"--workers must be at least 1, got {args.workers}")
    said, lefts = plan(jobs, args.workers if args.backend == "ray" else 1)
    print(said, file=sys.stderr)
    bar = tqdm(total=len(jobs), desc="campaign: training runs", unit="run")
    left_of = {str(job["out"]): left for job, left in zip(jobs, lefts, strict=True)}

    def done(job: dict, summary: dict) -> None:
        bar.update()
        record_run(job, left_of[str(job["out"])], summary)
        if not args.json:
            bar.write(run_line(job["estimator"], job["seed"], summary, job["out"]))

    try:
        runs = run_campaign(jobs, args.backend, args.workers, args.address, done)
    except KeyboardInterrupt:
        print(f"interrupted: rerun the same command to resume ({args.out})", file=sys.stderr)
        raise SystemExit(130) from None
    finally:
        bar.close()
    return {"runs": runs}


def run_line(estimator: str, seed: int, summary: dict, out: Path) -> str:
    """A finished training run in one line."""
    return (
        f"{estimator} seed {seed} ({summary['algo']}): {summary['timesteps']} decisions of "
        "reward learning, "
        f"{summary['wall_time_s']:.0f} s of training; {evaluation_line(summary)}. "
        f"Wrote {summary['model']}, {summary['learning_curve']}, {out}/train.json"
    )


def evaluation_line(summary: dict) -> str:
    """A training run's last evaluation in words: RL's (none runs before ``eval_freq`` steps),
    else the demonstration stage's last round."""
    last, stage = summary["last_evaluation"], summary.get("demonstrations")
    if last is not None:
        rate = last["success_rate"]
        return f"last evaluation (at {last['timesteps']} timesteps): success rate {rate:.2f}"
    if stage is not None:
        return (
            f"demonstrations, {stage['round']} rounds, kept round {stage['kept_round']}: "
            f"val success {stage['val_success']:.2f}"
        )
    return "no evaluation ran (fewer timesteps than eval_freq)"
