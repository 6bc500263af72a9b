"""``stsf-gym evaluate``: an agent driving on each estimator's pose, over seeded episodes.

Writes ``results.json`` (numbers: the results schema, :mod:`stsf_gym.results`), ``results.md``
(one row per estimator, :func:`~stsf_gym.experiments.statistics.summarise`, rendered from the
JSON), ``trajectories.png`` (true vs estimated paths over the map, with 2-sigma ellipses),
``errors.png`` (position and heading error against distance driven), ``nees.png`` (NEES over
time with its chi-square bounds) and each episode's TUM trajectories
(``episodes/trajectories/<episode>/{truth,estimate}.txt``). Finished episodes are kept in
``episodes/`` and reused by a rerun with the same ``--out``. With fault files, every fault
set runs on every estimator instead (:mod:`stsf_gym.experiments.fault_runs`).
"""

from __future__ import annotations

from pathlib import Path

from stsf_gym.agents.registry import check_agents, trained_on
from stsf_gym.episode_env import estimator_options
from stsf_gym.experiments.benchmark.trained import expand_agents
from stsf_gym.experiments.compare import compare
from stsf_gym.experiments.episodes import (
    EpisodeResult,
    EpisodeSpec,
    run_episodes,
    specs_config,
)
from stsf_gym.experiments.fault_runs import evaluate_faults
from stsf_gym.experiments.plotting.consistency import plot_nees
from stsf_gym.experiments.plotting.maps import plot_errors, plot_trajectories
from stsf_gym.experiments.reports import write_report
from stsf_gym.experiments.result_tables import results_tables
from stsf_gym.experiments.statistics import summarise
from stsf_gym.results import SCHEMA_VERSION
from stsf_gym.validation import ConfigError


def evaluate(
    out: str | Path,
    estimators: list[str],
    seeds: int,
    seed: int = 0,
    world: str = "irl_corridor",
    agent: str = "follower",
    workers: int = 2,
    env: dict | None = None,
    faults: list[str | Path] | None = None,
    agent_options: dict | None = None,
    record: dict | None = None,
    backend: str = "local",
    address: str | None = None,
) -> tuple[dict, dict[str, list[EpisodeResult]]]:
    """Run ``seeds`` episodes per estimator; write the table and figures to ``out``.

    Returns the summary (as written to results.json) and the episodes per estimator. With
    ``faults`` (fault files), the episodes run per fault set and estimator instead. With
    ``record`` (:func:`~stsf_gym.experiments.episodes.run_episode`) every episode is recorded.
    The episodes run in ``workers`` local processes or as Ray tasks (``backend`` ``ray``, on
    the cluster at ``address`` or a local instance).
    """
    if faults:
        if record:
            raise ConfigError("recording (--record) is not available with --faults")
        return evaluate_faults(
            out, estimators, seeds, seed, world, agent, workers, env or {}, faults, backend, address
        )
    out = Path(out)
    specs = [
        EpisodeSpec(
            world, estimator, s, agent, env or {}, estimator_options(estimator), agent_options or {}
        )
        for estimator in estimators
        for s in range(seed, seed + seeds)
    ]
    desc = f"evaluate {world}"
    results = run_episodes(specs, out / "episodes", workers, desc, record, backend, address)
    by_estimator = {e: [r for r in results if r.spec["estimator"] == e] for e in estimators}
    rows = [summarise(name, episodes, agent) for name, episodes in by_estimator.items()]
    summary = {
        "schema_version": SCHEMA_VERSION,
        "world": world,
        "agent": agent,
        "seeds": [seed, seed + seeds - 1],
        "rows": rows,
    }
    title = agent
    trained = trained_on(agent)
    if trained is not None:  # a learnt agent: record what it was trained on
        summary["trained"] = trained
        title += " ({algo} trained on {estimator}, {timesteps} steps)".format(**summary["trained"])
    table = results_tables(rows)
    write_report(
        out,
        summary,
        f"Evaluation: {title} on {world}",
        table,
        config=specs_config(specs),
        seeds=(spec.seed for spec in specs),
    )
    summary["figures"] = [
        str(plot_trajectories(world, by_estimator, out / "trajectories.png")),
        str(plot_errors(by_estimator, out / "errors.png")),
        str(plot_nees(by_estimator, out / "nees.png")),
    ]
    return summary, by_estimator


def evaluate_agents(
    out: str | Path,
    agents: list[str],
    estimators: list[str],
    seeds: int,
    seed: int = 0,
    world: str = "irl_corridor",
    workers: int = 2,
    env: dict | None = None,
    faults: list[str | Path] | None = None,
    record: dict | None = None,
    backend: str = "local",
    address: str | None = None,
) -> tuple[dict, Path]:
    """``stsf-gym evaluate``: one agent on every pose source (:func:`evaluate`), or, for several
    agents or a name with ``{estimator}`` (replaced by each pose source), the comparison table
    (:func:`~stsf_gym.experiments.compare.compare`). Every agent is made once first, so an
    unknown name or a missing model fails before any episode. Returns the summary and the
    Markdown report written. The episodes run in ``workers`` local processes or as Ray tasks
    (``backend``, ``address``)."""
    expanded = expand_agents(agents)
    check_agents(sorted({a.replace("{estimator}", e) for a in expanded for e in estimators}))
    out = Path(out)
    if len(expanded) > 1 or any("{estimator}" in agent for agent in agents):
        if record:
            raise ConfigError("--record records one agent's episodes, not a comparison")
        summary = compare(
            out, expanded, estimators, seeds, seed, world, workers, env, backend, address
        )
        return summary, out / "comparison.md"
    summary, _ = evaluate(
        out,
        estimators,
        seeds,
        seed,
        world,
        agents[0],
        workers,
        env,
        faults,
        record=record,
        backend=backend,
        address=address,
    )
    return summary, out / "results.md"
