"""``stsf-gym accuracy-curve``: how good must localization be for this agent?

Each agent drives on the ``degraded-truth`` pose source (:mod:`stsf_gym.estimators.
degraded_truth`) with its error model scaled by each level of the dial, over seeded episodes;
success rate, collisions and path-following error (RMS distance of the true robot from the
path) are set against the *measured* ATE of those episodes. The real estimators (odometry,
conventional fusion, STSF, EKF) run with the same agents and seeds and are placed on the
same axes as points. The reading is the agent's **tolerated ATE**: the largest measured ATE
of the dial's levels up to which the agent reaches the goal in at least
:data:`REQUIRED_SUCCESS` of episodes at every level.

Every episode is a cell (:mod:`stsf_gym.experiments.jobs.cells`), run on the job engine's
local or Ray backend with its resume: each finished cell is a row of ``<out>/cells.sqlite``.
Writes ``curve.json`` (numbers, the results schema), ``curve.md`` and ``curve.png``.
"""

from __future__ import annotations

from pathlib import Path

from stsf_gym.config_files import deep_merge
from stsf_gym.envs.config import load_config
from stsf_gym.envs.generated_env import parse_world
from stsf_gym.episode_env import NOT_CONFIG, estimator_options
from stsf_gym.experiments.curve.inputs import DIAL, check_dial_timing, check_request, curve_world
from stsf_gym.experiments.curve.plot import plot_curve
from stsf_gym.experiments.jobs.cells import CELL_JOBS
from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.io import markdown_table, write_atomic, write_json
from stsf_gym.results import SCHEMA_VERSION, rendered, stats
from stsf_gym.results.fingerprint import by_digest
from stsf_gym.results.provenance import provenance

DEFAULT_LEVELS = (0.5, 1.0, 2.0, 4.0, 6.0, 8.0, 11.0, 16.0)
DEFAULT_ESTIMATORS = ("odometry", "conventional", "stsf", "ekf")
REQUIRED_SUCCESS = 0.9
#: The dial needs no camera; the estimators see simulated detections unless ``env`` says else.
DIAL_ENV = {"camera": {"enabled": False}}
ESTIMATOR_ENV = {"camera": {"mode": "fast"}}
METRICS = (
    "success_rate",
    "collision_rate",
    "path_error_rms_m",
    "ate_rmse_m",
    "final_error_m",
    "rpe_trans_m_per_m",
    "nees_mean",
)


def curve_cells(
    agents: list[str],
    world: str,
    seeds: list[int],
    levels: list[float],
    estimators: list[str],
    env: dict,
    dial: dict,
) -> list[dict]:
    """The cells of the curve: each agent on each dial level and on each estimator."""
    cells = []
    for agent in agents:
        agent = str(Path(agent).resolve()) if agent.endswith(".zip") else agent
        for level in levels:
            options = {**estimator_options(DIAL), **dial, "scale": level}
            cells += _cells(agent, world, seeds, DIAL, deep_merge(env, DIAL_ENV), options, level)
        for estimator in estimators:
            env_e = deep_merge(ESTIMATOR_ENV, env)
            cells += _cells(agent, world, seeds, estimator, env_e, estimator_options(estimator))
    return cells


def _cells(agent, world, seeds, estimator, env, options, level=None) -> list[dict]:
    values = {"agent": agent, "estimator": estimator}
    if level is not None:
        values["scale"] = level
    return [
        {
            "kind": "evaluate",
            "world": world,
            "estimator": estimator,
            "agent": agent,
            "seed": seed,
            "faults": "none",
            "env": env,
            "options": options,
            "values": {**values, "seed": seed},
        }
        for seed in seeds
    ]


def accuracy_curve(
    out: str | Path,
    agents: list[str],
    world: str | None = None,
    seeds: int = 3,
    seed: int = 0,
    levels: list[float] = DEFAULT_LEVELS,
    estimators: list[str] = DEFAULT_ESTIMATORS,
    backend: str = "local",
    workers: int = 2,
    address: str | None = None,
    env: dict | None = None,
    dial: dict | None = None,
    suite: str | None = None,
) -> dict:
    """Run (or resume) every cell of the curve; write curve.json, curve.md and curve.png.
    ``world`` (default ``irl_corridor``), or ``suite``: the benchmark suite whose test worlds
    and task the curve drives on (``env`` over its episode env). Bad input is refused before
    any cell runs (:mod:`~stsf_gym.experiments.curve.inputs`)."""
    out, dial = Path(out), dial or {}
    check_request(agents, list(levels), dial)
    world, env = curve_world(world, env or {}, suite, seed, seeds)
    generated = parse_world(world) is not None
    config = {k: v for k, v in env.items() if k not in NOT_CONFIG}
    # a bad world or env key fails before anything runs
    loaded = load_config(config, world=None if generated else world)
    task = loaded.task
    check_dial_timing({**estimator_options(DIAL), **dial}, loaded.sim.max_episode_seconds)
    cells = curve_cells(
        agents, world, list(range(seed, seed + seeds)), sorted(levels), estimators, env, dial
    )
    ran = run_jobs(
        CELL_JOBS,
        cells,
        out / "cells.sqlite",
        "accuracy curve",
        backend,
        workers,
        address,
        unit="episode",
    )
    summary = summarise_curve(cells, ran.results)
    summary.update(
        schema_version=SCHEMA_VERSION,
        world=world,
        suite=suite,
        protocol=task.protocol,
        goal_radius_m=task.goal_radius if task.protocol == "declare" else None,
        seeds=[seed, seed + seeds - 1],
        dial={**estimator_options(DIAL), **dial},
    )
    summary["provenance"] = provenance(by_digest(ran.configs), (cell["seed"] for cell in cells))
    write_json(out / "curve.json", summary)
    write_atomic(out / "curve.md", curve_markdown(summary))
    summary["figures"] = [str(plot_curve(summary, out / "curve.png"))]
    return summary


def summarise_curve(cells: list[dict], results: list[dict]) -> dict:
    """Per agent: the dial's points (by level), its tolerated ATE, and the estimators' points."""
    groups: dict[tuple, list[dict]] = {}
    failed = []
    for cell, result in zip(cells, results, strict=True):
        if "error" in result:
            failed.append({"cell": cell["values"], "error": result["error"]})
            continue
        key = (cell["agent"], cell["estimator"], cell["values"].get("scale"))
        groups.setdefault(key, []).append(result["metrics"])
    curves, points = {}, []
    for (agent, estimator, scale), metrics in groups.items():
        summary = stats(metrics)
        row = {"estimator": estimator, **{k: summary[k] for k in METRICS if k in summary}}
        if estimator == DIAL:
            curves.setdefault(agent, []).append({"scale": scale, **row})
        else:
            points.append({"agent": agent, **row})
    agents = list(dict.fromkeys(cell["agent"] for cell in cells))
    return {
        "required_success_rate": REQUIRED_SUCCESS,
        "curves": [
            {
                "agent": agent,
                "label": agent_label(agent),
                "tolerated_ate_m": tolerated_ate(curves.get(agent, [])),
                "fails_within_levels": any(
                    level["success_rate"]["mean"] < REQUIRED_SUCCESS
                    for level in curves.get(agent, [])
                ),
                "levels": curves.get(agent, []),
            }
            for agent in agents
        ],
        "estimators": points,
        "failed": failed,
    }


def agent_label(agent: str) -> str:
    """``follower``, or a saved model's algorithm and the pose source it was trained on."""
    from stsf_gym.agents.registry import trained_on

    record = trained_on(agent)
    if record is None:
        return agent
    return f"{record['algo'].upper()} trained on {record['estimator']}"


def tolerated_ate(levels: list[dict]) -> float | None:
    """The largest measured ATE (mean) of the levels, in increasing order, up to which every
    level reaches the goal in at least :data:`REQUIRED_SUCCESS` of episodes (None: not even
    the smallest)."""
    tolerated = None
    for level in sorted(levels, key=lambda level: level["scale"]):
        if level["success_rate"]["mean"] < REQUIRED_SUCCESS:
            break
        tolerated = level["ate_rmse_m"]["mean"]
    return tolerated


def curve_markdown(summary: dict) -> str:
    """The reading, then one table per agent's dial and one of the estimators' points."""
    where = f"suite `{summary['suite']}`" if summary.get("suite") else summary["world"]
    text = f"# Accuracy curve on {where}\n\n"
    if summary.get("protocol") == "declare":
        text += (
            f"Declared arrival: a success is a declared stop within "
            f"{summary['goal_radius_m']} m of every goal.\n\n"
        )
    else:
        text += "Reach-the-goal protocol (the paper's): the true pose entering the goal circle.\n\n"
    for curve in summary["curves"]:
        ate = curve["tolerated_ate_m"]
        reading = "not even at the smallest level" if ate is None else f"up to ATE {ate:.3f} m"
        if ate is not None and not curve["fails_within_levels"]:
            reading = f"at every level, at least up to ATE {ate:.3f} m (add larger --levels)"
        text += (
            f"- **{curve['label']}** reaches the goal in >= {REQUIRED_SUCCESS:.0%} of "
            f"episodes {reading}\n"
        )
    for curve in summary["curves"]:
        rows = [rendered(level) for level in curve["levels"]]
        if rows:
            text += f"\n## {curve['label']} on `{DIAL}`\n\n" + markdown_table(rows)
    if summary["estimators"]:
        labels = {curve["agent"]: curve["label"] for curve in summary["curves"]}
        rows = [rendered({**p, "agent": labels[p["agent"]]}) for p in summary["estimators"]]
        text += "\n## The estimators on the same axes\n\n" + markdown_table(rows)
    if summary["failed"]:
        rows = [{"cell": str(f["cell"]), "error": f["error"]} for f in summary["failed"]]
        text += "\n## Failed cells\n\n" + markdown_table(rows)
    return text
