"""What a command prints when it is done: its Markdown report, and the cells that failed."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


class NothingFinished(RuntimeError):
    """Every cell of a command failed: its files are written, the command exits 1."""


def print_markdown(args: argparse.Namespace, path: Path) -> None:
    """The report ``path`` as a table on the terminal (nothing with ``--json``)."""
    if not args.json:  # rich loads here: stsf-gym --help and --json runs never need it
        from rich.console import Console

        from stsf_gym.terminal_table import print_markdown as print_table

        console = Console()
        print_table(path.read_text(), console, path.name)
        console.print(f"Wrote {path.parent}/")


def failed_cells(summary: dict, finished: int) -> dict:
    """Name each failed cell of ``summary`` on stderr; with ``finished`` results none (every
    cell failed), raise :class:`NothingFinished`."""
    for failed in summary["failed"]:
        print(f"failed cell {json.dumps(failed['cell'])}: {failed['error']}", file=sys.stderr)
    if summary["failed"] and not finished:
        raise NothingFinished(
            f"all {len(summary['failed'])} cell(s) failed (named above): nothing to score; "
            "the report written says so, and a rerun retries them"
        )
    return summary
