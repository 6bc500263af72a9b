"""``stsf-gym demo``: the follower on each pose source over a few sparse-suite test worlds
(declared arrival), a table with intervals, a paragraph saying what it shows, a trajectory
plot and one video made from the episodes driven."""

from __future__ import annotations

import argparse
import os

from rich.console import Console

from stsf_gym.cli import inputs, options
from stsf_gym.experiments.demo import DEMO_SUITE, DEMO_WORLDS, headline, run_demo
from stsf_gym.terminal_table import fit_table
from stsf_gym.validation import ConfigError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``demo``."""
    options.common(parser, "out/demo")
    parser.add_argument(
        "--worlds",
        type=options.whole,
        default=DEMO_WORLDS,
        help=f"{DEMO_SUITE} test worlds, one episode per pose source on each ({DEMO_WORLDS})",
    )
    parser.add_argument("--seconds", type=float, help="simulated time limit per episode")
    cores = os.cpu_count() or 1
    options.backend(parser, f"processes or local Ray CPUs ({cores}: the cores here)")
    parser.set_defaults(workers=cores)
    parser.add_argument(
        "--no-video", action="store_true", help="skip the video (made from the episodes driven)"
    )
    options.record(parser)


def run(args: argparse.Namespace) -> dict:
    """Run the demo; print its table, what it shows and the files it wrote."""
    inputs.check_counts(args)
    if args.worlds < 1:
        raise ConfigError(f"--worlds must be at least 1, got {args.worlds}")
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
    summary = run_demo(
        args.out,
        args.seed,
        args.workers,
        env,
        not args.no_video,
        args.worlds,
        inputs.recording(args),
        args.backend,
        args.address,
    )
    if not args.json:
        console = Console()
        title = (
            f"stsf-gym demo: the follower on {args.worlds} {DEMO_SUITE} test worlds "
            f"(seeds {args.seed}-{args.seed + args.worlds - 1}), declared arrival"
        )
        cells = headline(summary["rows"])
        rows = [list(row.values()) for row in cells]
        console.print(fit_table(list(cells[0]), rows, console.width, title, "results.md"))
        console.print()
        console.print(summary["paragraph"], markup=False, highlight=False)
        files = ["results.md", "results.json", *(f.split("/")[-1] for f in summary["figures"])]
        files += [summary["video"]] if "video" in summary else []
        console.print(f"\nWrote {args.out}/: {', '.join(files)}", markup=False, highlight=False)
    return summary
