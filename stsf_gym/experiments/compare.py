"""Agents x pose sources: the comparison table and figure of ``stsf-gym evaluate``.

``stsf-gym evaluate --agent follower,out/train/ppo-{estimator}/best/best_model.zip`` runs each
agent on each pose source; ``{estimator}`` in a model path is replaced by the pose source, so
each source is driven by the agent trained on it. Every pair runs the same seeded episodes as
:func:`stsf_gym.experiments.evaluate.evaluate` (same env, wrapper and scoring), in parallel,
with resume. Writes ``comparison.json`` (the results schema: numbers), ``comparison.md`` (one
row per pair: success rate, collisions, ATE, RPE, NEES, ...) and ``comparison.png`` (success
rate and RMS position error per pair).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stsf_gym.episode_env import estimator_options
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


def agent_name(template: str, estimator: str) -> str:
    """A short name for the table: ``follower``, or the algorithm of the saved model."""
    from stsf_gym.agents.registry import trained_on

    record = trained_on(agent_for(template, estimator))
    return template if record is None else record["algo"].upper()


def compare(
    out: str | Path,
    agents: list[str],
    estimators: list[str],
    seeds: int,
    seed: int = 0,
    world: str = "irl_corridor",
    workers: int = 2,
    env: dict | None = None,
) -> dict:
    """Run every agent on every pose source; write the table and the figure to ``out``."""
    out = Path(out)
    pairs = [(a, e) for a in agents for e in estimators]
    specs = [
        EpisodeSpec(world, e, s, agent_for(a, e), env or {}, estimator_options(e))
        for a, e in pairs
        for s in range(seed, seed + seeds)
    ]
    results = run_episodes(specs, out / "episodes", workers, desc=f"compare {world}")
    by_pair = {
        (agent_name(a, e), e): [
            r for r in results if r.spec["agent"] == agent_for(a, e) and r.spec["estimator"] == e
        ]
        for a, e in pairs
    }
    rows = [summarise(e, episodes, a) for (a, e), episodes in by_pair.items()]
    summary = {
        "schema_version": SCHEMA_VERSION,
        "world": world,
        "agents": agents,
        "seeds": [seed, seed + seeds - 1],
        "rows": rows,
    }
    table = markdown_table([rendered(row, SUMMARY_COLUMNS) for row in rows])
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
        ax_s.bar(x + i * width, success, width, label=agent)
        ax_e.bar(x + i * width, np.maximum(errors, 1e-4), width, label=agent)  # truth: 0 on log
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
