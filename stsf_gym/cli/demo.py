"""``stsf-gym demo``: the follower on each estimator on the IRL corridor, a table, a plot and
a video per estimator."""

from __future__ import annotations

import argparse

from rich.console import Console

from stsf_gym.cli import inputs, options
from stsf_gym.experiments.demo import COLUMNS, run_demo
from stsf_gym.results import rendered
from stsf_gym.terminal_table import fit_table
from stsf_gym.validation import ConfigError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``demo``."""
    options.common(parser, "out/demo")
    parser.add_argument("--seconds", type=float, help="simulated time limit per episode")
    parser.add_argument("--seeds", type=int, default=1, help="episodes per estimator (1)")
    options.backend(parser)
    parser.add_argument(
        "--video-seconds",
        type=float,
        help="simulated seconds of each estimator's episode in its video (default: the whole "
        "route, ten times faster than simulated time; 0: no videos)",
    )
    options.record(parser)


def run(args: argparse.Namespace) -> dict:
    """Run the demo; print its table and the files it wrote."""
    inputs.check_counts(args)
    env = inputs.env_overrides(args)
    if args.seconds is not None:
        if args.seconds <= 0:
            raise ConfigError(f"--seconds must be positive, got {args.seconds}")
        if "max_episode_seconds" in env.get("sim", {}):
            raise ConfigError(
                "--seconds and sim.max_episode_seconds (from --config or --set) both set the "
                "episode length; give one"
            )
        env.setdefault("sim", {})["max_episode_seconds"] = args.seconds
    if args.video_seconds is not None and args.video_seconds < 0:
        raise ConfigError(f"--video-seconds must be >= 0, got {args.video_seconds}")
    summary = run_demo(
        args.out,
        args.seed,
        args.workers,
        env,
        args.video_seconds,
        args.seeds,
        inputs.recording(args),
        args.backend,
        args.address,
    )
    if not args.json:
        console = Console()
        seeds = f"seed {args.seed}" if args.seeds == 1 else f"{args.seeds} seeds from {args.seed}"
        title = f"stsf-gym demo: follower on the IRL corridor ({seeds})"
        cells = [rendered(row, COLUMNS) for row in summary["rows"]]
        rows = [list(row.values()) for row in cells]
        console.print(fit_table(list(cells[0]), rows, console.width, title, "results.md"))
        videos = [str(args.out / v) for v in summary.get("videos", {}).values()]
        console.print(
            f"Wrote {args.out}/results.md, results.json, {', '.join(summary['figures'])}"
            + (f" and {', '.join(videos)}" if videos else "")
        )
    return summary
