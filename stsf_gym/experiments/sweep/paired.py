"""Paired differences of a sweep: a swept key's two values on the same seeds.

For every swept key with exactly two values, the cells that differ only in that key (every
other swept value and the seed alike) form pairs; per setting of the other swept values, the
success rate of the second value minus the first, with Newcombe's paired interval
(:func:`~stsf_gym.experiments.benchmark.intervals.newcombe_paired`). The episodes of a pair
share their world and every random stream but the one the key changes, so the interval is
that of the key's effect, not of the luck of the draw.
"""

from __future__ import annotations

import json

from stsf_gym.experiments.benchmark.intervals import newcombe_paired


def paired_differences(cells: list[dict], results: list[dict]) -> list[dict]:
    """The paired success differences of every two-valued swept key (finished pairs only)."""
    swept: dict[str, list] = {}
    for cell in cells:
        for key, value in cell["values"].items():
            if key != "seed" and value not in swept.setdefault(key, []):
                swept[key].append(value)
    differences = []
    for key, values in swept.items():
        if len(values) != 2:
            continue
        pairs: dict[str, dict] = {}
        for cell, result in zip(cells, results, strict=True):
            if "outcome" not in result:  # failed (or a cell kind without episodes)
                continue
            others = {k: v for k, v in cell["values"].items() if k not in (key, "seed")}
            slot = pairs.setdefault(json.dumps(others, sort_keys=True), {"others": others})
            side = slot.setdefault(values.index(cell["values"][key]), {})
            side[cell["seed"]] = result["outcome"] == "goal"
        for slot in pairs.values():
            first, second = slot.get(0, {}), slot.get(1, {})
            seeds = sorted(set(first) & set(second))
            if seeds:
                difference = newcombe_paired([second[s] for s in seeds], [first[s] for s in seeds])
                differences.append(
                    {"key": key, "values": values, "others": slot["others"], **difference}
                )
    return differences
