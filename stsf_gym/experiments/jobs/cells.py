"""Cells: the episode and training jobs the sweep, the benchmark and the accuracy curve run.

A cell is a JSON-friendly dict (``kind``, ``world``, ``estimator``, ``agent``, ``seed``,
``env`` overrides, the estimator's ``options``, the swept ``values``; training cells also
``train`` and their run folder ``out``). A kind's ``run`` takes the cell and returns a dict
whose ``metrics`` (numbers or booleans) the sweep summarises over seeds; its optional
``check`` raises ConfigError on a bad cell before anything runs. :func:`run_cell` never
raises: an error becomes a result with the error's text, so one failed cell does not stop
the rest. :data:`CELL_JOBS` is the cells' kind of job for
:func:`~stsf_gym.experiments.jobs.engine.run_jobs`: keyed by :func:`cell_name`, resolved by
:func:`cell_config`.
"""

from __future__ import annotations

import hashlib
import json
import traceback
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

from stsf_gym.config_files import deep_merge
from stsf_gym.experiments.jobs.checks import cell_problem
from stsf_gym.experiments.jobs.spec import JobKind, failure, full_disk_error
from stsf_gym.validation import ConfigError

#: ``train`` keys that are arguments of ``stsf_gym.agents.training.train.train`` (with their
#: defaults in a sweep: one env per cell); every other ``train`` key is a hyper-parameter
#: override.
TRAIN_ARGUMENTS = {"algo": "ppo", "timesteps": None, "n_envs": 1, "config": None}


@dataclass(frozen=True)
class CellKind:
    """What a kind of sweep cell does: ``run`` a cell, and ``check`` one before anything runs."""

    run: Callable[[dict], dict]
    check: Callable[[dict], None] | None = None


def cell_kind(kind: str) -> CellKind:
    """The :class:`CellKind` named ``kind`` (``evaluate`` or ``train``); ConfigError otherwise."""
    if kind not in CELL_KINDS:
        raise ConfigError(f"unknown cell kind {kind!r}; known: {', '.join(CELL_KINDS)}")
    return CELL_KINDS[kind]


def run_cell(cell: dict) -> dict:
    """Run ``cell`` with its kind's function; an exception becomes ``{"error": ...}``, but a
    full disk (``ENOSPC``) is raised: it stops the sweep (:func:`~.spec.full_disk_error`)."""
    try:
        return cell_kind(cell["kind"]).run(cell)
    except Exception as err:
        if full_disk_error(err) is not None:
            raise
        return failure(err, traceback.format_exc())


def cell_name(cell: dict) -> str:
    """File name of a cell: readable prefix, digest of its swept values."""
    digest = hashlib.sha1(json.dumps(cell["values"], sort_keys=True).encode()).hexdigest()
    return f"{cell['kind']}-{cell['estimator']}-seed{cell['seed']}-{digest[:10]}"


def evaluate_cell(cell: dict) -> dict:
    """One episode of the agent on the estimator's pose: its outcome, the metrics of the
    results schema (:func:`stsf_gym.experiments.statistics.episode_metrics`) and what the agent
    did near its goals
    (:func:`~stsf_gym.experiments.benchmark.agent_behaviour.episode_behaviour`)."""
    from stsf_gym.experiments.benchmark.agent_behaviour import episode_behaviour
    from stsf_gym.experiments.episodes import EpisodeSpec, run_episode
    from stsf_gym.experiments.statistics import episode_metrics

    spec = EpisodeSpec(
        cell["world"], cell["estimator"], cell["seed"], cell["agent"], cell["env"], cell["options"]
    )
    record = cell.get("record")  # benchmark --record: the episode written as a log too
    episode = run_episode(spec, record) if record else run_episode(spec)
    return {
        "outcome": episode.outcome,
        "distance": episode.distance,
        "metrics": episode_metrics(episode),
        "navigation": {  # what the declared-stop task scores (stsf_gym.experiments.benchmark)
            "goals": episode.goals,
            "route_length_m": episode.route_length,
            "geodesic_length_m": route_geodesic_m(cell, episode.true_poses[0][:2]),
            "stops": episode.stops,
        },
        "behaviour": episode_behaviour(episode),
    }


def route_geodesic_m(cell: dict, start) -> float:
    """SPL's shortest path of an evaluate cell's episode: the geodesic length (m) from its true
    ``start`` (x, y) through the goals its task visits, with walls and obstacles grown by the
    robot's radius (:mod:`stsf_gym.envs.worlds.geodesic`). The route is the whole one: an
    episode on a training leg (``task.leg_max`` above 0) draws its goal at reset, unrecorded."""
    from stsf_gym.envs.generated_env import episode_config
    from stsf_gym.envs.task import PathTask
    from stsf_gym.envs.worlds.geodesic import route_geodesic_length

    cfg = episode_config(cell["world"], cell["seed"], cell["env"])
    goals = PathTask(cfg.world, cfg.reward, cfg.task).goals
    return route_geodesic_length(cfg.world, start, cfg.robot.body_radius, goals)


def train_cell(cell: dict) -> dict:
    """Train an SB3 agent on the cell's pose source (in ``cell["out"]``, resumable), then
    evaluate the model for one episode on an evaluation seed, as an evaluate cell does."""
    from stsf_gym.agents.training.train import EVAL_SEED_OFFSET, train

    arguments, hyperparams = _train_arguments(cell)
    summary = train(
        arguments["algo"],
        cell["estimator"],
        Path(cell["out"]),
        arguments["timesteps"],
        cell["seed"],
        cell["world"],
        arguments["config"],
        hyperparams,
        arguments["n_envs"],
        progress_bar=False,
    )
    evaluation = evaluate_cell(
        {
            **cell,
            "agent": summary["model"],
            "env": summary["env"],  # the env it was trained in (hyper-parameter file + cell)
            "seed": cell["seed"] + EVAL_SEED_OFFSET,
        }
    )
    last = summary["last_evaluation"] or {}
    evaluation["metrics"]["timesteps"] = summary["timesteps"]
    if "success_rate" in last:
        evaluation["metrics"]["training_eval_success_rate"] = last["success_rate"]
    return {**evaluation, "model": summary["model"], "train_wall_time_s": summary["wall_time_s"]}


def cell_config(cell: dict) -> dict:
    """Every value ``cell`` runs with (the configuration its saved result must match): the
    episode's resolved env and pose-source settings, and the agent's settings or, for a
    training cell, its training arguments and hyper-parameters as resolved from their files."""
    from stsf_gym.episode_env import resolved_config
    from stsf_gym.experiments.episodes import agent_config

    resolved = resolved_config(cell["world"], cell["estimator"], cell["env"], cell["options"])
    if cell["kind"] != "train":
        return {**resolved, "agent": agent_config(cell["agent"])}
    from stsf_gym.agents.training.hyperparams import load_hyperparams
    from stsf_gym.agents.training.train import env_id_for

    arguments, hyperparams = _train_arguments(cell)
    env_id = env_id_for(cell["world"], cell["estimator"])
    hp = load_hyperparams(arguments["algo"], env_id, arguments["config"], hyperparams)
    return {**resolved, "train": {"arguments": arguments, "hyperparams": asdict(hp)}}


def check_train_cell(cell: dict) -> None:
    """The trainer must be installed and the cell's hyper-parameters valid."""
    try:
        from stsf_gym.agents.training.hyperparams import load_hyperparams
        from stsf_gym.agents.training.train import env_id_for
    except ImportError as err:
        raise ConfigError(f"cell kind 'train' is not available: {err}") from err
    arguments, hyperparams = _train_arguments(cell)
    env_id = env_id_for(cell["world"], cell["estimator"])
    load_hyperparams(arguments["algo"], env_id, arguments["config"], hyperparams)


def _train_arguments(cell: dict) -> tuple[dict, dict]:
    """``train(...)`` arguments, and hyper-parameter overrides (the cell's env included)."""
    options = cell["train"]
    arguments = {key: options.get(key, default) for key, default in TRAIN_ARGUMENTS.items()}
    hyperparams = {k: v for k, v in options.items() if k not in TRAIN_ARGUMENTS}
    return arguments, deep_merge(hyperparams, {"env": cell["env"]})


#: Cell kinds by name.
CELL_KINDS: dict[str, CellKind] = {
    "evaluate": CellKind(evaluate_cell),
    "train": CellKind(train_cell, check_train_cell),
}

#: Cells as jobs of the engine.
CELL_JOBS = JobKind(run_cell, cell_name, cell_config, cell_problem)
