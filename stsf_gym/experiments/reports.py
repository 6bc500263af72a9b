"""Reports of the experiments: each result as JSON beside a titled Markdown table, atomically.

An experiment's ``results.json`` (or ``<name>.json``) is its summary as returned to the CLI;
the Markdown file beside it is the same in a table for people.
"""

from __future__ import annotations

from pathlib import Path

from stsf_gym.io import write_atomic, write_json


def write_report(
    out: Path,
    summary: dict,
    title: str,
    body: str,
    json_name: str = "results.json",
    markdown_name: str = "results.md",
) -> None:
    """``summary`` to ``out/json_name`` and ``# title`` and ``body`` to ``out/markdown_name``."""
    write_json(out / json_name, summary)
    write_atomic(out / markdown_name, f"# {title}\n\n{body}")
