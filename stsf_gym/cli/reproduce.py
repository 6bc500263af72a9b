"""``stsf-gym reproduce table1|fig10|fig11``: the paper's experiments."""

from __future__ import annotations

import argparse

from stsf_gym.cli import inputs, options
from stsf_gym.cli.reports import print_markdown
from stsf_gym.config import parse_overrides
from stsf_gym.experiments.fig10_11 import fig10, fig11
from stsf_gym.experiments.table1.run import run_table1


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``reproduce``."""
    parser.add_argument("experiment", choices=["table1", "fig10", "fig11"])
    options.common(parser, "out")
    parser.add_argument("--seeds", type=options.whole, help="seeds (table1: config, 20; figs: 10)")
    options.workers(parser)


def run(args: argparse.Namespace) -> dict:
    """Run the experiment into ``OUT/<experiment>/``; print its report."""
    inputs.check_counts(args)
    out = args.out / args.experiment
    if args.experiment in ("fig10", "fig11"):
        figure = fig10 if args.experiment == "fig10" else fig11
        summary = figure(out, args.seeds or 10, args.seed, args.workers, inputs.env_overrides(args))
        print_markdown(args, out / f"{args.experiment}.md")
        return summary
    overrides = parse_overrides(args.overrides)
    if args.seeds is not None:
        overrides["seeds"] = args.seeds
    summary = run_table1(out, seed=args.seed, config=args.config, workers=args.workers, **overrides)
    print_markdown(args, out / "table1.md")
    return summary
