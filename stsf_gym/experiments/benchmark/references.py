"""Each learnt agent against its references on the same pose source and test worlds: the
scripts that drove beside it (the follower, the cautious follower) and, for a fine-tuned
training folder, its own clones (``clone:FOLDER``, the policy each reward stage started from).

Per training folder, pose source and reference, two answers:

- **over the seeds**: the interquartile mean of the runs' success minus the reference's, with a
  95 % interval from a paired two-level bootstrap (:func:`paired_seed_iqm`: worlds and runs
  resampled alike for both sides, a run paired with its own clone, a script repeated for
  every run), so "at least the clone + 0.10" reads off the interval;
- **run by run**: each run's success minus the reference's on the worlds both finished
  (a clone the same seed's), Newcombe's paired interval.
"""

from __future__ import annotations

from stsf_gym.agents.registry import CAUTIOUS_FOLLOWER, FOLLOWER
from stsf_gym.agents.resolve import CLONE_PREFIX
from stsf_gym.experiments.benchmark.intervals import newcombe_paired, paired_seed_iqm
from stsf_gym.experiments.benchmark.small_samples import interval, noted
from stsf_gym.experiments.benchmark.trained import agent_name, training_groups
from stsf_gym.io import markdown_table

SCRIPTS = (FOLLOWER, CAUTIOUS_FOLLOWER)


def against_references(scores: dict[tuple[str, str], dict[int, dict]]) -> list[dict]:
    """One entry per training folder (clones excluded), pose source and reference that drove
    there: the IQM difference over runs and each run's paired difference (see the module)."""
    groups = training_groups(scores)
    entries = []
    for (group, estimator), runs in groups.items():
        if group.startswith(CLONE_PREFIX):
            continue
        references = {
            script: [scores[script, estimator]] * len(runs)
            for script in SCRIPTS
            if (script, estimator) in scores
        }
        clones = groups.get((CLONE_PREFIX + group, estimator), [])
        if len(clones) == len(runs):
            references["clone"] = [scores[clone, estimator] for clone in clones]
        for reference, sides in references.items():
            mine = [scores[run, estimator] for run in runs]
            worlds = sorted(set.intersection(*(set(s) for s in (*mine, *sides))))
            if not worlds:
                continue
            first = [[bool(run[w]["success"]) for w in worlds] for run in mine]
            second = [[bool(side[w]["success"]) for w in worlds] for side in sides]
            entries.append(
                {
                    "agent": group,
                    "estimator": estimator,
                    "reference": reference,
                    "runs": len(runs),
                    "worlds": len(worlds),
                    "success_iqm_difference": paired_seed_iqm(first, second),
                    "paired_per_run": [
                        newcombe_paired(a, b) for a, b in zip(first, second, strict=True)
                    ],
                }
            )
    return entries


def references_markdown(entries: list[dict]) -> str:
    """The entries as a table: the IQM difference and its interval, and each run's."""
    table = [
        {
            "agent": agent_name(e["agent"]),
            "pose source": e["estimator"],
            "minus": e["reference"],
            "success IQM difference (95 % CI)": interval(e["success_iqm_difference"], e["worlds"]),
            "per run (Newcombe 95 % CI)": "; ".join(
                interval(p, e["worlds"]) for p in e["paired_per_run"]
            ),
            "worlds": e["worlds"],
        }
        for e in entries
    ]
    return (
        "\n## Learnt agents against their references, paired on the same worlds\n\n"
        "Success minus the reference's: over the training runs (IQM, paired two-level "
        "bootstrap over worlds and runs; a run paired with its own clone) and run by run.\n\n"
        + noted(markdown_table(table), min(e["worlds"] for e in entries))
    )
