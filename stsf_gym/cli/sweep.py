"""``stsf-gym sweep``: a grid of evaluation or training cells from a sweep file."""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.cli import inputs, options
from stsf_gym.cli.reports import failed_cells, print_markdown
from stsf_gym.experiments.sweep.run import run_sweep


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``sweep``."""
    parser.add_argument("file", type=Path, help="sweep YAML, e.g. configs/sweeps/noise.yaml")
    options.common(parser, "out/sweeps")
    options.backend(parser)


def run(args: argparse.Namespace) -> dict:
    """Run (or resume) the sweep into ``OUT/<file's stem>/``; print its report."""
    inputs.check_counts(args)
    out = args.out / args.file.stem
    summary = run_sweep(
        args.file,
        out,
        args.backend,
        args.workers,
        args.address,
        args.seed,
        inputs.env_overrides(args),
    )
    print_markdown(args, out / "results.md")
    return failed_cells(summary, finished=summary["finished"])
