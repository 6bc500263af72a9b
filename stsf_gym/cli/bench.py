"""``stsf-gym bench``: the speed figures beside their targets."""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.bench import run_bench, run_step_bench
from stsf_gym.bench.step import check_baseline
from stsf_gym.cli import options
from stsf_gym.cli.reports import print_markdown
from stsf_gym.validation import ConfigError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``bench``."""
    options.common(parser, "out/bench")
    parser.add_argument(
        "--seconds", type=float, default=60.0, help="simulated seconds per camera case (60)"
    )
    parser.add_argument(
        "--vector-steps",
        type=options.whole,
        default=1000,
        help="vector-env steps per worker count (AsyncVectorEnv, SubprocVecEnv; rendered, fast)",
    )
    parser.add_argument(
        "--step-only", action="store_true", help="only the step section (env steps/s)"
    )
    parser.add_argument(
        "--steps", type=options.whole, default=1500, help="timed env steps per step case (1500)"
    )
    parser.add_argument(
        "--rounds",
        type=options.whole,
        default=5,
        help="fresh processes per step case and side, the best kept (5)",
    )
    parser.add_argument(
        "--baseline",
        type=Path,
        help="another checkout's folder or a Python with another stsf-gym installed: the step "
        "section runs on it too, side by side, with the ratio",
    )


def run(args: argparse.Namespace) -> dict:
    """Measure; print the report."""
    if args.seconds <= 0 or min(args.vector_steps, args.steps, args.rounds) < 1:
        raise ConfigError(
            "--seconds must be positive, --vector-steps, --steps and --rounds at least 1"
        )
    if args.baseline is not None:
        check_baseline(args.baseline)
    if args.step_only:
        summary = run_step_bench(args.out, args.steps, args.seed, args.baseline, args.rounds)
    else:
        summary = run_bench(
            args.out, args.seconds, args.vector_steps, args.seed, args.baseline, args.rounds
        )
    print_markdown(args, args.out / "bench.md")
    return summary
