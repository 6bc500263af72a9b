"""The benchmark's headline comparison, said in words: each learnt agent beside the follower on
the same pose source, on the same test worlds.

Per training folder (or shipped agent) and pose source, from ``results.json``'s ``trained``
entries: the interquartile mean of success over the training seeds against the follower's
rate, their ratio, and each seed's success minus the follower's, paired world by world, with
Newcombe's 95 % interval; a seed whose interval excludes 0 is above or below the follower.
"""

from __future__ import annotations

from stsf_gym.agents.registry import FOLLOWER
from stsf_gym.experiments.benchmark.small_samples import interval, noted
from stsf_gym.experiments.benchmark.trained import agent_name
from stsf_gym.io import markdown_table


def entry_models(summary: dict, entry: dict) -> list[str]:
    """The model of each run of a ``trained`` entry; for results written before the entries
    listed them, the rows of its pose source named after its agent, in order."""
    if "models" in entry:
        return entry["models"]
    prefix = agent_name(entry["agent"]) + "/"
    return [
        row["agent"]
        for row in summary["rows"]
        if row["estimator"] == entry["estimator"] and agent_name(row["agent"]).startswith(prefix)
    ]


def seed_names(summary: dict, entry: dict) -> list[str]:
    """The name of each run of a ``trained`` entry (``ppo-stsf/seed-0``)."""
    models = entry_models(summary, entry)
    if len(models) != entry["runs"]:
        return [f"{agent_name(entry['agent'])} run {i + 1}" for i in range(entry["runs"])]
    return [agent_name(model) for model in models]


def follower_pairs(summary: dict) -> list[tuple[str, str, dict]]:
    """``(model, pose source, paired difference)`` of every learnt model the follower drove
    beside: the model's success minus the follower's on the worlds both finished."""
    pairs = []
    for entry in summary.get("trained", []):
        for name, paired in zip(
            seed_names(summary, entry), entry.get("paired_vs_follower", []), strict=False
        ):
            pairs.append((name, entry["estimator"], paired))
    return pairs


def _count(count: int, noun: str) -> str:
    return f"{count} {noun}" if count == 1 else f"{count} {noun}s"


def _side(paired: dict) -> str:
    if paired["low"] > 0:
        return "above"
    return "below" if paired["high"] < 0 else "level"


def _follower_row(summary: dict, estimator: str) -> dict | None:
    for row in summary["rows"]:
        if row["agent"] == FOLLOWER and row["estimator"] == estimator:
            return row
    return None


def _sentence(summary: dict, entry: dict) -> str:
    """One learnt agent on one pose source against the follower, in words."""
    name, source = agent_name(entry["agent"]), entry["estimator"]
    trained = entry.get("trained_on")
    deployed = f" (trained on {trained})" if trained and trained != source else ""
    low, high = entry["success_iqm_ci95"]
    seeds = _count(entry["runs"], "training seed")
    head = (
        f"- **{name}**{deployed} on {source}, {seeds}: success IQM "
        f"{entry['success_iqm']:.2f} (95 % CI {low:.2f}-{high:.2f})"
    )
    follower = _follower_row(summary, source)
    if "paired_vs_follower" not in entry or follower is None:
        return (
            f"{head}; the follower did not drive on {source} in this run (name `follower` in "
            f"`--agents`, and {source} in `--estimators` if given, to compare)."
        )
    rate, (f_low, f_high) = follower["success_rate"]["mean"], follower["success_ci95"]
    ratio = entry.get("ratio_to_follower")
    ratio_text = (
        f"{ratio:.2f} times its rate" if ratio is not None else "the follower never succeeded"
    )
    sides = [_side(p) for p in entry["paired_vs_follower"]]
    return (
        f"{head} against the follower's {rate:.2f} ({f_low:.2f}-{f_high:.2f}) on the same "
        f"{_count(entry['worlds'], 'world')}, {ratio_text}; paired world by world (the table "
        "below), "
        f"{sides.count('below')} of {len(sides)} below the follower, {sides.count('above')} "
        f"above, {sides.count('level')} not told apart."
    )


def against_follower_markdown(summary: dict) -> str:
    """The section of the leaderboard comparing each learnt agent with the follower: a line
    per agent and pose source, and a row per model (empty without learnt agents)."""
    entries = summary.get("trained", [])
    if not entries:
        return ""
    text = (
        "\n## Learnt agents beside the follower on the same pose source\n\n"
        "Success over the same test worlds and episode seeds; a difference whose interval "
        "excludes 0 tells the two apart (Newcombe 1998, method 10); the IQM is over the "
        "training seeds.\n\n"
    )
    text += "\n".join(_sentence(summary, entry) for entry in entries) + "\n"
    rows = []
    by_model = {(r["agent"], r["estimator"]): r for r in summary["rows"]}
    for entry in entries:
        models = entry_models(summary, entry)
        pairs = entry.get("paired_vs_follower") or [None] * entry["runs"]
        follower = _follower_row(summary, entry["estimator"])
        for model, name, paired in zip(models, seed_names(summary, entry), pairs, strict=False):
            row = by_model.get((model, entry["estimator"]))
            rows.append(
                {
                    "agent": name,
                    "pose source": entry["estimator"],
                    "success": f"{row['success_rate']['mean']:.2f}" if row else "-",
                    "follower": f"{follower['success_rate']['mean']:.2f}" if follower else "-",
                    "difference (95 % CI)": interval(paired, paired["pairs"]) if paired else "-",
                    "vs follower": _side(paired) if paired else "-",
                }
            )
    return text + "\n" + noted(markdown_table(rows), min(e["worlds"] for e in entries))
