"""``stsf-gym replay``: pose sources rerun on recorded MCAP logs, no simulator."""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.cli import inputs, options
from stsf_gym.cli.reports import print_markdown
from stsf_gym.recording import require_recording
from stsf_gym.validation import ConfigError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``replay``."""
    parser.add_argument("files", nargs="+", type=Path, metavar="FILE.mcap", help="MCAP logs")
    options.common(parser, "out/replay")
    parser.add_argument(
        "--estimators",
        default=options.ALL_ESTIMATORS,
        help="comma-separated pose sources (as evaluate's)",
    )


def run(args: argparse.Namespace) -> dict:
    """Replay the logs; print the report."""
    require_recording("stsf-gym replay")
    from stsf_gym.experiments import replay  # needs the record extra: checked above

    if args.config or args.overrides:
        raise ConfigError("replay runs the logs as recorded: it takes no --config or --set")
    estimators = inputs.pose_sources(args.estimators)
    summary = replay.replay_logs(args.files, estimators, args.out)
    print_markdown(args, args.out / "results.md")
    return summary
