"""``stsf-gym evaluate``: an agent on each pose source over many seeds, or several agents
compared."""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.cli import inputs, options
from stsf_gym.cli.reports import print_markdown
from stsf_gym.experiments.evaluate import evaluate_agents


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``evaluate``."""
    options.common(parser, "out/evaluate")
    options.agents(
        parser,
        default="follower",
        help_text="follower, cautious-follower, a model saved by train (DIR/model.zip), a train "
        "--seeds folder or a shipped agent (pretrained:SUITE/ALGO-SOURCE); several, "
        "comma-separated, give one "
        "comparison table; {estimator} in a path is replaced by each pose source",
    )
    parser.add_argument(
        "--estimators",
        default=options.ALL_ESTIMATORS,
        help="comma-separated pose sources: odometry, conventional (the paper's: current pair "
        "only), conventional-filter, stsf, ekf, smoother, mcl, truth, degraded-truth, or your "
        "own as package.module:Class (e.g. examples.complementary:ComplementaryFilter)",
    )
    options.world(parser)
    parser.add_argument("--seeds", type=options.whole, default=5, help="episodes per estimator (5)")
    options.backend(parser)
    parser.add_argument(
        "--faults",
        nargs="+",
        type=Path,
        metavar="FILE",
        help="fault files (e.g. configs/faults/*.yaml): each fault set x each estimator",
    )
    options.record(parser)


def run(args: argparse.Namespace) -> dict:
    """Evaluate (or compare) the agents; print the report."""
    inputs.check_counts(args)
    estimators = inputs.pose_sources(args.estimators)
    world = inputs.world(args)
    summary, report = evaluate_agents(
        args.out,
        inputs.names(args.agents, "--agents"),
        estimators,
        args.seeds,
        args.seed,
        world,
        args.workers,
        inputs.env_overrides(args, world),
        args.faults,
        inputs.recording(args),
        args.backend,
        args.address,
    )
    print_markdown(args, report)
    return summary
