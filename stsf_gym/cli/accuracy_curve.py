"""``stsf-gym accuracy-curve``: success against localization error, how good must it be?"""

from __future__ import annotations

import argparse

from stsf_gym.cli import inputs, options
from stsf_gym.cli.reports import failed_cells, print_markdown
from stsf_gym.config import parse_overrides
from stsf_gym.envs.suite import suite_names
from stsf_gym.experiments.benchmark.trained import expand_agents
from stsf_gym.experiments.curve.run import accuracy_curve
from stsf_gym.validation import ConfigError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``accuracy-curve``."""
    options.common(parser, "out/accuracy_curve")
    options.agents(
        parser,
        default="follower",
        help_text="follower, cautious-follower, saved models, train --seeds folders and/or shipped "
        "agents "
        "(pretrained:SUITE/ALGO-SOURCE: one curve per training seed), comma-separated",
    )
    parser.add_argument(
        "--world",
        help=f"world name or YAML path (default {options.DEFAULT_WORLD}; not with --suite)",
    )
    parser.add_argument(
        "--suite",
        choices=suite_names(),
        help="a benchmark suite's test worlds and declared-stop task instead of --world",
    )
    parser.add_argument("--seeds", type=options.whole, default=3, help="episodes per point (3)")
    parser.add_argument(
        "--levels",
        default="0.5,1,2,4,6,8,11,16",
        help="dial levels: scales of configs/estimators/degraded-truth.yaml's errors",
    )
    parser.add_argument(
        "--dial",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a degraded-truth option, e.g. latency_s=0.3 or rate_hz=2",
    )
    parser.add_argument(
        "--estimators",
        default=options.ALL_ESTIMATORS,
        help="estimators placed as points on the curve (comma-separated; '' for none)",
    )
    options.backend(parser)


def run(args: argparse.Namespace) -> dict:
    """Run (or resume) the curve; print its report."""
    inputs.check_counts(args)
    agents = expand_agents(inputs.names(args.agents, "--agents"))
    estimators = inputs.pose_sources(args.estimators, empty_ok=True)  # points: optional
    levels = _levels(args.levels)
    world = None if args.suite else args.world or options.DEFAULT_WORLD
    summary = accuracy_curve(
        args.out,
        agents,
        world,
        args.seeds,
        args.seed,
        levels,
        estimators,
        args.backend,
        args.workers,
        args.address,
        inputs.env_overrides(args, world),
        parse_overrides(args.dial),
        args.suite,
    )
    print_markdown(args, args.out / "curve.md")
    finished = len(summary["estimators"]) + sum(len(c["levels"]) for c in summary["curves"])
    return failed_cells(summary, finished)


def _levels(text: str) -> list[float]:
    """The numbers of ``--levels``: each a number, none given twice (the same level's cells
    would be run and counted twice)."""
    levels = []
    for level in text.split(","):
        try:
            levels.append(float(level))
        except ValueError as err:
            raise ConfigError(f"--levels must be comma-separated numbers, got {text!r}") from err
    twice = sorted({level for level in levels if levels.count(level) > 1})
    if twice:
        raise ConfigError(f"--levels gives the level {twice[0]:g} twice, got {text!r}")
    return levels
