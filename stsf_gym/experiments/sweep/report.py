"""A sweep's summary: ``results.json``, ``results.md`` and ``errors.png``.

Evaluation sweeps also get the paired differences in success of each two-valued swept key
(:mod:`stsf_gym.experiments.sweep.paired`).

Cells that differ only in their seed form a group; each metric of a group is a
:func:`stsf_gym.results.stat` over its finished cells (mean, std, count and the per-seed
values; a rate is the mean of 0/1 values). ``errors.png`` has one panel per swept numeric
``env.*`` key: final (solid, with one std) and RMS (ATE, dashed) position error against the
swept value, one line per estimator, both axes logarithmic (the value axis when its values are
positive), means over seeds and any other swept values.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from stsf_gym.experiments.sweep.paired import paired_differences
from stsf_gym.experiments.sweep.spec import Sweep
from stsf_gym.io import markdown_table, save_figure, write_atomic, write_json
from stsf_gym.results import METRICS, SCHEMA_VERSION, render, stats
from stsf_gym.results.fingerprint import by_digest
from stsf_gym.results.provenance import provenance

FINAL, RMS = "final_error_m", "ate_rmse_m"
FIGURE = "errors.png"


def write_report(sweep: Sweep, results: list[dict], out: Path, configs: dict[str, dict]) -> dict:
    """Summarise the cells' ``results``; write the files to ``out``; return the summary. Its
    provenance holds each distinct resolved configuration once (by digest) and, per cell
    file name, the digest of the configuration it ran with (``configs``: by cell name)."""
    groups = [_group(label, members) for label, members in _by_group(sweep.cells, results)]
    failed = [
        {"cell": cell["values"], "error": result["error"]}
        for cell, result in zip(sweep.cells, results, strict=True)
        if "error" in result
    ]
    figure = plot_errors(sweep.cells, results, out / FIGURE)
    summary = {
        "schema_version": SCHEMA_VERSION,
        "sweep": sweep.name,
        "file": str(sweep.path),
        "kind": sweep.kind,
        "cells": len(results),
        "finished": len(results) - len(failed),
        "failed": failed,
        "groups": groups,
        "paired": paired_differences(sweep.cells, results) if sweep.kind == "evaluate" else [],
        "figures": [FIGURE] if figure else [],
    }
    seeds = (cell["seed"] for cell in sweep.cells)
    summary["provenance"] = provenance(by_digest(configs), seeds)
    write_json(out / "results.json", summary)
    write_atomic(out / "results.md", markdown(sweep.name, groups, failed, summary["paired"]))
    return summary


def markdown(name: str, groups: list[dict], failed: list[dict], paired: list[dict]) -> str:
    """One row per group: its swept values ("base" where a key keeps the base value); then
    the paired differences in success of each two-valued swept key."""
    keys = list(dict.fromkeys(key for group in groups for key in group["values"]))
    rows = []
    for group in groups:
        row = {_column(k): _value(group["values"].get(k, "base")) for k in keys}
        row.update(seeds=group["cells"] - group["failed"], failed=group["failed"])
        row.update({METRICS.get(k, k): render(v) for k, v in group["metrics"].items()})
        rows.append(row)
    columns = list(dict.fromkeys(column for row in rows for column in row))
    text = f"# Sweep: {name}\n\n" + markdown_table(rows, columns)
    if paired:
        text += "\n## Paired differences in success (Newcombe 1998, method 10)\n\n"
        text += markdown_table(
            [
                {
                    "key": f"{_column(p['key'])}: {_value(p['values'][1])} - "
                    f"{_value(p['values'][0])}",
                    "other values": ", ".join(
                        f"{_column(k)} {_value(v)}" for k, v in p["others"].items()
                    ),
                    "pairs": p["pairs"],
                    "difference (95 % CI)": f"{p['difference']:+.3f} ({p['low']:+.3f} to "
                    f"{p['high']:+.3f})",
                    "only second / only first": f"{p['only_first']} / {p['only_second']}",
                }
                for p in paired
            ]
        )
    if failed:
        text += "\n## Failed cells\n\n" + markdown_table(
            [
                {"cell": json.dumps(f["cell"]), "error": f["error"].replace("|", "\\|")}
                for f in failed
            ]
        )
    return text


def plot_errors(cells: list[dict], results: list[dict], path: Path) -> Path | None:
    """Position error against each swept numeric ``env.*`` key; None when there is none."""
    from matplotlib.figure import Figure

    swept = _noise_levels(cells)
    if not swept:
        return None
    fig = Figure(figsize=(5.5 * len(swept), 4.2))
    for ax, key in zip(fig.subplots(1, len(swept), squeeze=False)[0], swept, strict=True):
        for estimator, levels in _levels(cells, results, key).items():
            xs = sorted(levels)
            final = [[m[FINAL] for m in levels[x]] for x in xs]
            rms = [np.mean([m[RMS] for m in levels[x]]) for x in xs]
            line = ax.errorbar(
                xs, np.mean(final, axis=1), np.std(final, axis=1), marker="o", capsize=3
            )
            line[0].set_label(estimator)
            ax.plot(xs, rms, ls="--", color=line[0].get_color())
        if min(swept[key]) > 0:
            ax.set_xscale("log")
        levels = sorted(set(swept[key]))
        ax.set_xticks(levels, [f"{level:g}" for level in levels], minor=False)
        ax.set_xticks([], minor=True)
        ax.set_yscale("log")  # errors span orders of magnitude across estimators
        ax.set(xlabel=_column(key), ylabel="position error (m)", title=_column(key))
        ax.legend(title="final (solid), RMS (dashed)", fontsize=8)
    return save_figure(fig, path)


def _by_group(cells: list[dict], results: list[dict]) -> list[tuple[dict, list[dict]]]:
    groups: dict[str, tuple[dict, list[dict]]] = {}
    for cell, result in zip(cells, results, strict=True):
        label = {k: v for k, v in cell["values"].items() if k != "seed"}
        groups.setdefault(json.dumps(label, sort_keys=True), (label, []))[1].append(result)
    return list(groups.values())


def _group(label: dict, results: list[dict]) -> dict:
    finished = [r["metrics"] for r in results if "error" not in r]
    return {
        "values": label,
        "cells": len(results),
        "failed": len(results) - len(finished),
        "metrics": stats(finished),
    }


def _noise_levels(cells: list[dict]) -> dict[str, list[float]]:
    """The swept ``env.*`` keys whose values are all numbers, with those values."""
    swept: dict[str, list] = {}
    for cell in cells:
        for key, value in cell["values"].items():
            if key.startswith("env."):
                swept.setdefault(key, []).append(value)
    return {
        key: values
        for key, values in swept.items()
        if all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
    }


def _levels(cells: list[dict], results: list[dict], key: str) -> dict[str, dict]:
    """Metrics of the finished cells that set ``key``, by estimator then value."""
    levels: dict[str, dict] = {}
    for cell, result in zip(cells, results, strict=True):
        metrics = result.get("metrics", {})
        if key in cell["values"] and FINAL in metrics and RMS in metrics:
            by_value = levels.setdefault(cell["estimator"], {})
            by_value.setdefault(cell["values"][key], []).append(metrics)
    return levels


def _column(key: str) -> str:
    return key.removeprefix("env.")


def _value(value) -> str:
    return value if isinstance(value, str) else json.dumps(value)
