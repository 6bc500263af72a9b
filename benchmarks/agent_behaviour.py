"""What each agent does near its goals, on a suite's test worlds: the measures of
:mod:`stsf_gym.experiments.benchmark.agent_behaviour` (where and how it declares, its approach,
how far it leaves the route, boards in view, collisions) beside its success, every agent on
the same worlds and seeds as ``stsf-gym benchmark`` runs them (its cells, world by world).

The benchmark keeps scores, not trajectories; this runs the episodes again through
``run_episodes``, which keeps each whole episode (and resumes from ``OUT/episodes``).

Usage::

    python benchmarks/agent_behaviour.py --suite sparse --estimators stsf \
        --agents follower,cautious-follower,MODEL --worlds 20 --workers 2 --out OUT

Writes ``behaviour.json`` (numbers only: per agent and pose source, each measure's
``{mean, std, count, values}``) and ``behaviour.md`` to ``OUT``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.envs.suite import load_suite
from stsf_gym.experiments.benchmark.agent_behaviour import (
    EPISODE_MEASURES,
    STOP_MEASURES,
    behaviour_row,
    episode_behaviour,
)
from stsf_gym.experiments.benchmark.run import benchmark_cells
from stsf_gym.experiments.episodes import EpisodeSpec, run_episodes
from stsf_gym.io import write_atomic, write_json
from stsf_gym.results.provenance import portable, provenance

COLUMNS = ("success", *STOP_MEASURES, *EPISODE_MEASURES)


def behaviours(
    suite: str, agents: list[str], estimators: list[str], worlds: int, workers: int, out: Path
) -> list[dict]:
    """One row per agent and pose source (:func:`behaviour_row`) over ``worlds`` test worlds."""
    cells = benchmark_cells(load_suite(suite), agents, estimators, list(range(worlds)))
    specs = [
        EpisodeSpec(c["world"], c["estimator"], c["seed"], c["agent"], c["env"], c["options"])
        for c in cells
    ]
    episodes = run_episodes(specs, out / "episodes", workers, f"behaviour {suite}")
    groups: dict[tuple[str, str], list[dict]] = {}
    for spec, episode in zip(specs, episodes, strict=True):
        groups.setdefault((spec.agent, spec.estimator), []).append(episode_behaviour(episode))
    return [
        {"agent": portable(agent), "estimator": estimator, **behaviour_row(rows)}
        for (agent, estimator), rows in groups.items()
    ]


def markdown(rows: list[dict], worlds: int) -> str:
    """The rows as a table: each measure's mean (stop measures over every declared stop)."""
    head = ["agent", "pose source", *COLUMNS]
    lines = [
        f"Means over {worlds} test worlds (stop measures over every declared stop).",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for row in rows:
        cells = [row["agent"], row["estimator"]]
        cells += ["-" if row[c]["mean"] is None else f"{row[c]['mean']:.2f}" for c in COLUMNS]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--suite", default="sparse")
    parser.add_argument("--agents", default="follower,cautious-follower")
    parser.add_argument("--estimators", default="stsf")
    parser.add_argument("--worlds", type=int, default=20)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    rows = behaviours(
        args.suite,
        args.agents.split(","),
        args.estimators.split(","),
        args.worlds,
        args.workers,
        args.out,
    )
    write_json(args.out / "behaviour.json", {"rows": rows, "provenance": provenance()})
    write_atomic(args.out / "behaviour.md", markdown(rows, args.worlds))
    print(markdown(rows, args.worlds))


if __name__ == "__main__":
    main()
