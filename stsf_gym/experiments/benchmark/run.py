"""``stsf-gym benchmark --suite NAME``: agents x pose sources x a suite's test worlds.

Agents: the follower on each pose source, and trained models (or training folders of several
seeds) on their own pose source, aggregated over training seeds
(:mod:`~stsf_gym.experiments.benchmark.trained`).

Every episode is a cell (``kind: evaluate``, :mod:`stsf_gym.experiments.jobs.cells`) on
world ``generated:test`` with the suite's generator and env (the declared-stop task, the fast
sensor mode): episode seed ``s`` drives test world ``first + s``, the same world and seed for
every agent and pose source, so pose sources are compared **paired**. The cells run on the
job engine's local or Ray backend and resume (each finished cell is a JSON file in
``<out>/cells/``). Writes ``results.json`` (the results schema: one row per agent and pose
source, per-episode values kept; the paired differences; the worlds' measured landmark
coverage; what each agent does near its goals,
:mod:`~stsf_gym.experiments.benchmark.agent_behaviour`), ``leaderboard.md`` and
``leaderboard.png``.
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path

from stsf_gym.agents.registry import trained_on
from stsf_gym.envs.config import load_config
from stsf_gym.envs.generated_env import check_distinct_worlds, world_seed_for
from stsf_gym.envs.suite import Suite, load_suite
from stsf_gym.envs.task import Polyline
from stsf_gym.envs.worlds.coverage import landmark_coverage
from stsf_gym.envs.worlds.generator import generate_world
from stsf_gym.episode_env import estimator_options
from stsf_gym.experiments.benchmark.agent_behaviour import behaviour_row
from stsf_gym.experiments.benchmark.figure import plot_leaderboard
from stsf_gym.experiments.benchmark.intervals import newcombe_paired, paired_bootstrap
from stsf_gym.experiments.benchmark.references import against_references
from stsf_gym.experiments.benchmark.report import leaderboard_markdown
from stsf_gym.experiments.benchmark.scores import episode_scores, leaderboard_row
from stsf_gym.experiments.benchmark.trained import (
    agent_pose_sources,
    aggregate_runs,
    expand_agents,
    paired_across_sources,
)
from stsf_gym.experiments.jobs.cells import CELL_JOBS
from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.io import write_atomic, write_json
from stsf_gym.results import SCHEMA_VERSION, check_rows, stat
from stsf_gym.results.fingerprint import by_digest
from stsf_gym.results.provenance import provenance
from stsf_gym.validation import ConfigError

WORLD = "generated:test"


def benchmark_cells(
    suite: Suite, agents: list[str], estimators: list[str] | None, seeds: list[int]
):
    """One evaluate cell per agent, pose source and episode seed (the pose sources of
    :func:`~stsf_gym.experiments.benchmark.trained.agent_pose_sources`); world by world, so a
    run cut short has every agent and pose source on the same worlds."""
    cells, expanded = [], expand_agents(agents)
    learnt_sources = [record["estimator"] for a in expanded if (record := trained_on(a))]
    drives = [
        (agent, estimator)
        for agent in expanded
        for estimator in agent_pose_sources(agent, estimators, learnt_sources)
    ]
    for seed, (agent, estimator) in itertools.product(seeds, drives):
        cells.append(
            {
                "kind": "evaluate",
                "world": WORLD,
                "estimator": estimator,
                "agent": agent,
                "seed": seed,
                "faults": "none",
                "env": suite.episode_env,
                "options": estimator_options(estimator),
                "values": {"suite": suite.name, "agent": agent, "estimator": estimator},
            }
        )
    return cells


def benchmark(
    out: str | Path,
    suite: str,
    agents: list[str] = ("follower",),
    estimators: list[str] | None = None,
    worlds: int = 100,
    seed: int = 0,
    backend: str = "local",
    workers: int = 2,
    address: str | None = None,
    record: dict | None = None,
) -> dict:
    """Run (or resume) the benchmark; write results.json, leaderboard.md and .png. With
    ``record`` (:func:`~stsf_gym.experiments.episodes.run_episode`) every episode is recorded
    too (a cell finished without its recording is run again)."""
    out, loaded = Path(out), load_suite(suite)
    if worlds < 1:
        raise ConfigError(f"--worlds must be at least 1, got {worlds}")
    test_worlds = loaded.generator_config().split_range("test")
    check_distinct_worlds(
        test_worlds, range(seed, seed + worlds), f"--seed {seed} --worlds {worlds}"
    )
    seeds = list(range(seed, seed + worlds))
    request = {"agents": list(agents), "estimators": estimators, "worlds": worlds, "seed": seed}
    check_same_request(out / "results.json", request)
    cells = benchmark_cells(loaded, list(agents), estimators, seeds)
    if record:
        cells = [{**cell, "record": record} for cell in cells]
    desc = f"benchmark {loaded.name}"
    ran = run_jobs(
        CELL_JOBS, cells, out / "cells.sqlite", desc, backend, workers, address, unit="episode"
    )
    own_sources = {
        agent: record["estimator"]
        for agent in dict.fromkeys(cell["agent"] for cell in cells)
        if (record := trained_on(agent))
    }
    summary = summarise_benchmark(loaded, cells, ran.results, own_sources)
    summary["worlds"] = worlds_summary(loaded, seeds)
    summary["request"] = request
    summary["provenance"] = provenance(by_digest(ran.configs), seeds)
    check_rows(summary["rows"])
    write_json(out / "results.json", summary)
    write_atomic(out / "leaderboard.md", leaderboard_markdown(summary))
    summary["figures"] = [str(plot_leaderboard(summary, out / "leaderboard.png"))]
    return summary


def check_same_request(results: Path, request: dict) -> None:
    """Refuse to write over ``results`` (an earlier run's ``results.json``) the report of
    another benchmark: other pose sources or first seed, fewer worlds, or agents that leave
    one of its agents out. The same request resumes or reruns it, and one that keeps every
    earlier agent and world extends it (a long run reported on the worlds it has finished,
    then on all; agents trained later added beside the earlier ones); a report from before
    requests were recorded is not compared."""
    if not results.is_file():
        return
    try:
        earlier = json.loads(results.read_text()).get("request")
    except (ValueError, AttributeError):
        return  # unreadable: nothing to keep; the run writes it anew
    if earlier is not None and earlier != request and not _extends(request, earlier):
        differ = [key for key in request if earlier.get(key) != request[key]]
        said = "; ".join(
            f"{key} {earlier.get(key)!r} there, {request[key]!r} now" for key in differ
        )
        raise ConfigError(
            f"{results.parent} holds the report of another benchmark ({said}); give another "
            "--out (its cells.sqlite may be copied there: finished cells are reused)"
        )


def _extends(request: dict, earlier: dict) -> bool:
    """Whether ``request`` keeps every agent and test world of ``earlier``, with the same
    pose sources and first seed (every row of the earlier report is in the new one)."""
    fewer, agents = earlier.get("worlds"), earlier.get("agents")
    return (
        all(earlier.get(key) == request[key] for key in ("estimators", "seed"))
        and isinstance(fewer, int)
        and request["worlds"] >= fewer
        and isinstance(agents, list)
        and set(agents) <= set(request["agents"])
    )


def summarise_benchmark(
    suite: Suite, cells: list[dict], results: list[dict], own_sources: dict[str, str] | None = None
) -> dict:
    """Rows per (agent, pose source), paired differences of every pair of pose sources per
    agent (on the seeds both finished), the learnt agents over their training seeds and
    against the follower (``own_sources``: each model's training pose source), what each
    agent does near its goals on each pose source, and the cells that failed to run."""
    scores: dict[tuple[str, str], dict[int, dict]] = {}
    behaviours: dict[tuple[str, str], list[dict]] = {}
    failed = []
    for cell, result in zip(cells, results, strict=True):
        if "error" in result:
            failed.append(
                {"cell": cell["values"] | {"seed": cell["seed"]}, "error": result["error"]}
            )
            continue
        key = (cell["agent"], cell["estimator"])
        scores.setdefault(key, {})[cell["seed"]] = episode_scores(result)
        behaviours.setdefault(key, []).append(result["behaviour"])
    rows = [
        leaderboard_row(agent, estimator, list(by_seed.values()), list(by_seed))
        for (agent, estimator), by_seed in scores.items()
    ]
    paired = []
    for (agent, first), (agent_b, second) in itertools.combinations(scores, 2):
        if agent != agent_b:
            continue
        common = sorted(set(scores[agent, first]) & set(scores[agent_b, second]))
        a = [scores[agent, first][s] for s in common]
        b = [scores[agent, second][s] for s in common]
        success = newcombe_paired([x["success"] for x in a], [y["success"] for y in b])
        paired.append(
            {
                "agent": agent,
                "first": first,
                "second": second,
                "success_difference": success,
                "success_differs": success["low"] > 0 or success["high"] < 0,
                "spl_difference": paired_bootstrap([x["spl"] for x in a], [y["spl"] for y in b]),
            }
        )
    return {
        "schema_version": SCHEMA_VERSION,
        "suite": suite.name,
        "protocol": "declare",
        "world": WORLD,
        "goal_radius_m": load_config(suite.env).task.goal_radius,
        "seeds": [min(c["seed"] for c in cells), max(c["seed"] for c in cells)],
        "rows": rows,
        "trained": aggregate_runs(scores, own_sources),
        "trained_paired": paired_across_sources(scores, own_sources),
        "against_references": against_references(scores),
        "paired": paired,
        "behaviour": [
            {"agent": agent, "estimator": estimator, **behaviour_row(rows)}
            for (agent, estimator), rows in behaviours.items()
        ],
        "failed": failed,
    }


def worlds_summary(suite: Suite, seeds: list[int]) -> dict:
    """The test worlds' measured landmark coverage, longest dark stretch and route."""
    gen, env = suite.generator_config(), load_config(suite.env)
    split = gen.split_range("test")
    coverage, dark, goals, length = [], [], [], []
    for seed in seeds:
        world = generate_world(world_seed_for(split, seed), gen, env)
        measured = landmark_coverage(world, gen, env)
        coverage.append(measured.fraction)
        dark.append(measured.longest_dark_m)
        goals.append(len(world.goals))
        length.append(Polyline(world.path).length)
    return {
        "world_seeds": [split[seeds[0] % len(split)], split[seeds[-1] % len(split)]],
        "coverage_configured": list(gen.visibility.coverage),
        "coverage": stat(coverage),
        "longest_dark_m": stat(dark),
        "goals": stat(goals),
        "path_length_m": stat(length),
    }
