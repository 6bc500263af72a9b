"""Agents x pose sources: the comparison table and figure of ``stsf-gym evaluate``.

``stsf-gym evaluate --agent follower,out/train/ppo-{estimator}/best/best_model.zip`` runs each
agent on each pose source; ``{estimator}`` in a model path is replaced by the pose source, so
each source is driven by the agent trained on it. Every pair runs the same seeded episodes as
:func:`stsf_gym.experiments.evaluate.evaluate` (same env, wrapper and scoring), in parallel,
with resume. Every model is its own row, named as the benchmark names it (a shipped agent's seed
``dagger-truth/seed-0``; the JSON keeps the whole path), and the seeds of one trained
agent are also aggregated as the benchmark aggregates them (IQM over seeds, two-level bootstrap
interval). Writes ``comparison.json`` (the results schema: numbers), ``comparison.md`` (one row
per pair: success rate, collisions, ATE, RPE, NEES, ...; then the seeds together) and
``comparison.png`` (success rate and RMS position error per pair).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stsf_gym.agents.registry import make_agent
from stsf_gym.config_files import deep_merge
from stsf_gym.episode_env import estimator_options
from stsf_gym.experiments.benchmark.intervals import seed_iqm
from stsf_gym.experiments.benchmark.trained import agent_name, training_groups
from stsf_gym.experiments.episodes import (
    EpisodeResult,
    EpisodeSpec,
    run_episodes,
    specs_config,
)
from stsf_gym.experiments.plotting.maps import pyplot
from stsf_gym.experiments.reports import write_report
from stsf_gym.experiments.statistics import rms, summarise
from stsf_gym.io import markdown_table, save_figure
from stsf_gym.results import SCHEMA_VERSION, rendered
from stsf_gym.validation import ConfigError

SUMMARY_COLUMNS = (
    "agent",
    "estimator",
    "episodes",
    "success_rate",
    "collision_rate",
    "time_limit_rate",
    "distance_before_failure_m",
    "ate_rmse_m",
    "rpe_trans_m_per_m",
    "final_error_m",
    "rms_heading_error_deg",
    "nees_mean",
)


def agent_for(template: str, estimator: str) -> str:
    """The agent that drives on ``estimator``: ``{estimator}`` in a path is filled in."""
    return template.replace("{estimator}", estimator)


def judged_alike(agents: list[str], estimators: list[str], env: dict) -> dict:
    """The env settings every row runs with: where an agent declares arrival with its STOP entry
    (its own task, :meth:`~stsf_gym.agents.registry.Agent.env_overrides`), its task protocol for
    every row, so the follower beside it is judged by the same rule."""
    protocols = {
        make_agent(agent_for(a, e)).env_overrides().get("task", {}).get("protocol")
        for a in agents
        for e in estimators
    } - {None}
    if len(protocols) > 1:
        raise ConfigError(f"the agents need different task protocols: {sorted(protocols)}")
    return deep_merge(env, {"task": {"protocol": protocols.pop()}}) if protocols else env


def seed_aggregates(by_pair: dict[tuple[str, str], list[EpisodeResult]]) -> list[dict]:
    """Per training folder (or shipped agent) and pose source with several models: the IQM over
    models of each model's success rate over the episodes, with its two-level bootstrap interval
    (episodes and models resampled), as the benchmark aggregates training seeds over worlds."""
    aggregates = []
    for (group, estimator), models in training_groups(by_pair).items():
        if len(models) < 2:
            continue
        seeds = sorted(
            set.intersection(*({r.spec["seed"] for r in by_pair[m, estimator]} for m in models))
        )
        matrix = [
            [
                float(r.outcome == "goal")
                for r in sorted(by_pair[m, estimator], key=_seed)
                if r.spec["seed"] in seeds
            ]
            for m in models
        ]
        interval = seed_iqm(matrix)
        aggregates.append(
            {
                "agent": group,
                "estimator": estimator,
                "runs": len(models),
                "episodes": len(seeds),
                "success_iqm": interval["estimate"],
                "success_iqm_ci95": [interval["low"], interval["high"]],
                "success_per_run": interval["per_run"],
            }
        )
    return aggregates


def _seed(result: EpisodeResult) -> int:
    return result.spec["seed"]


def _aggregates_markdown(aggregates: list[dict]) -> str:
    """The seeds of each trained agent together, as a table (empty without any)."""
    if not aggregates:
        return ""
    rows = [
        {
            "agent": agent_name(a["agent"]),
            "pose source": a["estimator"],
            "runs": a["runs"],
            "success IQM (95 % CI)": f"{a['success_iqm']:.2f} "
            f"({a['success_iqm_ci95'][0]:.2f}-{a['success_iqm_ci95'][1]:.2f})",
        }
        for a in aggregates
    ]
    return (
        "\n\n## Training seeds together\n\nInterquartile mean over the seeds of each seed's "
        "success rate, 95 % interval resampling episodes and seeds (as `stsf-gym benchmark`).\n\n"
        + markdown_table(rows)
    )


def compare(
    out: str | Path,
    agents: list[str],
    estimators: list[str],
    seeds: int,
    seed: int = 0,
    world: str = "irl_corridor",
    workers: int = 2,
    env: dict | None = None,
    backend: str = "local",
    address: str | None = None,
) -> dict:
    """Run every agent on every pose source (in ``workers`` local processes or as Ray tasks:
    ``backend``, ``address``); write the table and the figure to ``out``."""
    out = Path(out)
    env = judged_alike(agents, estimators, env or {})
    pairs = [(a, e) for a in agents for e in estimators]
    specs = [
        EpisodeSpec(world, e, s, agent_for(a, e), env or {}, estimator_options(e))
        for a, e in pairs
        for s in range(seed, seed + seeds)
    ]
    desc = f"compare {world}"
    results = run_episodes(specs, out / "episodes", workers, desc, backend=backend, address=address)
    by_pair = {  # each model its own row, under the name the benchmark gives it
        (agent_for(a, e), e): [
            r for r in results if r.spec["agent"] == agent_for(a, e) and r.spec["estimator"] == e
        ]
        for a, e in pairs
    }
    rows = [summarise(e, episodes, a) for (a, e), episodes in by_pair.items()]
    aggregates = seed_aggregates(by_pair)
    summary = {
        "schema_version": SCHEMA_VERSION,
        "world": world,
        "agents": agents,
        "seeds": [seed, seed + seeds - 1],
        "rows": rows,
        "aggregates": aggregates,
    }
    named = [{**row, "agent": agent_name(row["agent"])} for row in rows]
    table = markdown_table([rendered(row, SUMMARY_COLUMNS) for row in named])
    table += _aggregates_markdown(aggregates)
    write_report(
        out,
        summary,
        f"Agents x pose sources on {world}",
        table,
        "comparison.json",
        "comparison.md",
        config=specs_config(specs),
        seeds=range(seed, seed + seeds),
    )
    summary["figures"] = [str(plot_comparison(by_pair, out / "comparison.png"))]
    return summary


def plot_comparison(by_pair: dict[tuple[str, str], list[EpisodeResult]], path: Path) -> Path:
    """Grouped bars per pose source: success rate and RMS position error, one bar per agent."""
    plt = pyplot()
    agents = list(dict.fromkeys(a for a, _ in by_pair))
    estimators = list(dict.fromkeys(e for _, e in by_pair))
    width = 0.8 / len(agents)
    x = np.arange(len(estimators))
    fig, (ax_s, ax_e) = plt.subplots(1, 2, figsize=(12, 4))
    for i, agent in enumerate(agents):
        runs = [by_pair[agent, e] for e in estimators]
        success = [np.mean([r.outcome == "goal" for r in episodes]) for episodes in runs]
        errors = [np.mean([rms(r.errors) for r in episodes]) for episodes in runs]
        ax_s.bar(x + i * width, success, width, label=agent_name(agent))
        ax_e.bar(
            x + i * width, np.maximum(errors, 1e-4), width, label=agent_name(agent)
        )  # truth: 0 on log
    for ax, label in ((ax_s, "success rate"), (ax_e, "RMS position error (m)")):
        ax.set_xticks(x + width * (len(agents) - 1) / 2, estimators)
        ax.set_ylabel(label)
        ax.grid(axis="y", alpha=0.3)
    ax_s.set_ylim(0, 1.05)
    ax_e.set_yscale("log")
    ax_s.legend()
    episodes = sum(len(runs) for runs in by_pair.values())
    fig.suptitle(f"Agents x pose sources ({episodes} episodes)")
    fig.tight_layout()
    return save_figure(fig, path)
