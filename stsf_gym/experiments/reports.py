"""Reports of the experiments: each result as JSON beside a titled Markdown table, atomically.

An experiment's ``results.json`` (or ``<name>.json``) is its summary as returned to the CLI,
with the :func:`~stsf_gym.results.provenance.provenance` of the run under ``provenance``; the
Markdown file beside it is the same in a table for people.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

from stsf_gym.io import write_atomic, write_json
from stsf_gym.results.provenance import provenance


def write_report(
    out: Path,
    summary: dict,
    title: str,
    body: str,
    json_name: str = "results.json",
    markdown_name: str = "results.md",
    *,
    config: Mapping,
    seeds: Iterable[int],
) -> None:
    """``summary`` (its provenance added: the resolved ``config`` and the ``seeds`` run) to
    ``out/json_name`` and ``# title`` and ``body`` to ``out/markdown_name``."""
    summary["provenance"] = provenance(config, seeds)
    write_json(out / json_name, summary)
    write_atomic(out / markdown_name, f"# {title}\n\n{body}")
