"""``stsf-gym benchmark``: agents x pose sources on a suite's test worlds, the leaderboard."""

from __future__ import annotations

import argparse

from stsf_gym.agents.registry import check_agents
from stsf_gym.cli import inputs, options
from stsf_gym.cli.reports import failed_cells, print_markdown
from stsf_gym.envs.suite import suite_names
from stsf_gym.experiments.benchmark.run import benchmark
from stsf_gym.experiments.benchmark.trained import expand_agents
from stsf_gym.validation import ConfigError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``benchmark``."""
    options.common(
        parser, "out/benchmark", out_help="output folder: the results go to OUT/<suite>/"
    )
    parser.add_argument("--suite", required=True, choices=suite_names(), help="difficulty")
    options.agents(
        parser,
        default="follower",
        help_text="follower, cautious-follower, saved models, training folders (train --seeds N), "
        "their clones (clone:FOLDER: the policy each reward stage started from) and/or shipped "
        "agents (pretrained:SUITE/ALGO-SOURCE), comma-separated; a model drives on the pose "
        "source it was trained on",
    )
    parser.add_argument(
        "--estimators",
        help="pose sources, comma-separated: every agent drives on each (a learnt agent "
        "trained on one, deployed on each); without it, a learnt agent drives on its own and "
        "the scripts on those of the run's learnt agents (without learnt agents: odometry, "
        "conventional, conventional-filter, stsf and ekf)",
    )
    parser.add_argument("--worlds", type=options.whole, default=100, help="test worlds (100)")
    options.backend(parser)
    options.record(parser)


def run(args: argparse.Namespace) -> dict:
    """Run (or resume) the benchmark into ``OUT/<suite>/``; print the leaderboard."""
    inputs.check_counts(args)
    if args.config or args.overrides:
        raise ConfigError("benchmark runs a suite as written: edit or copy its configs/suites file")
    estimators = None if args.estimators is None else inputs.pose_sources(args.estimators)
    agents = expand_agents(inputs.names(args.agents, "--agents"))
    check_agents(agents)
    out = args.out / args.suite
    summary = benchmark(
        out,
        args.suite,
        agents,
        estimators,
        args.worlds,
        args.seed,
        args.backend,
        args.workers,
        args.address,
        inputs.recording(args, out),
    )
    print_markdown(args, out / "leaderboard.md")
    return failed_cells(summary, finished=len(summary["rows"]))
