"""Trained agents in the benchmark: each training seed's model, and the aggregate over seeds.

An agent of ``stsf-gym benchmark --agents`` is any name :mod:`stsf_gym.agents.resolve` reads:
``follower``, a shipped agent, a saved model (``.zip``), a training folder (its models) or
``clone:<training folder>`` (the clone each of its reward stages started from). A
model drives on the pose source it was trained on (its ``stsf_meta``); the follower on each pose
source asked for.

The models of one training folder are one agent trained with several seeds: besides a row per
model, the leaderboard aggregates them as rliable does (Agarwal et al. 2021, "Deep RL at the
edge of the statistical precipice"): the **interquartile mean** over runs of each run's mean
score over the test worlds (success, SPL), with a 95 % two-level bootstrap interval that
resamples worlds and runs (:func:`~stsf_gym.experiments.benchmark.intervals.seed_iqm`), so
the interval carries the spread between training seeds, not only between worlds.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np

from stsf_gym.agents import pretrained
from stsf_gym.agents.pretrained.shipped_folder import is_agent_folder
from stsf_gym.agents.registry import FOLLOWER, trained_on
from stsf_gym.agents.resolve import CLONE_PREFIX, SEED_FOLDERS, resolve_agent, training_group
from stsf_gym.agents.training_folder import CLONE, MODEL
from stsf_gym.experiments.benchmark.intervals import newcombe_paired, seed_iqm
from stsf_gym.validation import ConfigError

__all__ = ["SEED_FOLDERS", "expand_agents", "training_group"]  # also read from here


#: The pose sources of agents with none of their own when ``--estimators`` is not given.
DEFAULT_ESTIMATORS = ("odometry", "conventional", "conventional-filter", "stsf", "ekf")


def expand_agents(agents: list[str]) -> list[str]:
    """Each of ``agents`` as the single agents it stands for
    (:func:`~stsf_gym.agents.resolve.resolve_agent`: shipped agents and training folders as
    their models, one per training seed). Two names of the same model (an alias and its
    shipped name, a folder and its model) are refused: its episodes would count twice."""
    named_by: dict[str, str] = {}
    for agent in agents:
        for single in resolve_agent(agent):
            if single in named_by:
                raise ConfigError(
                    f"{named_by[single]!r} and {agent!r} name the same agent ({single}): "
                    "name it once"
                )
            named_by[single] = agent
    return list(named_by)


def agent_name(agent: str) -> str:
    """The short name the report gives an agent: ``follower``; a training folder by its name
    (``ppo-stsf``); a shipped agent without its prefix and suite (``ppo-truth``); a model by
    its training folder's or shipped agent's name with its seed (``ppo-stsf/seed-0``,
    ``ppo-truth/seed-0``), or by its file's stem when it is neither. The JSON keeps the whole
    path."""
    if agent.startswith(CLONE_PREFIX):
        return f"{agent_name(agent.removeprefix(CLONE_PREFIX))} clone"
    path = Path(agent)
    if path.suffix != ".zip":
        return path.name
    if path.match(f"*/{CLONE}"):
        return f"{agent_name(str(path.parent.parent / MODEL))} clone"
    folder = path.parent
    # <shipped-agents folder>/<suite>/<agent>/seed-S.zip
    if folder.parent.parent.name == pretrained.MODELS.name or is_agent_folder(folder):
        return f"{folder.name}/{path.stem}"
    if path.name != "model.zip":
        return path.stem
    return f"{folder.parent.name}/{folder.name}" if folder.match(SEED_FOLDERS) else folder.name


def agent_pose_sources(
    agent: str, estimators: list[str] | None, learnt_sources: list[str] = ()
) -> list[str]:
    """The pose sources ``agent`` drives on: those of ``estimators`` when given (a learnt agent
    trained on one, deployed on each: protocol (a)); without, a learnt agent its own (protocol
    (b)) and any other agent ``learnt_sources``, the pose sources the run's learnt agents
    drive on, so each is paired with the scripts on its own (no episode on a pose source no
    learnt agent of the run uses), or :data:`DEFAULT_ESTIMATORS` in a run of scripts alone."""
    if estimators is not None:
        return list(estimators)
    record = trained_on(agent)
    if record is not None:
        return [record["estimator"]]
    return list(dict.fromkeys(learnt_sources or DEFAULT_ESTIMATORS))


def training_groups(rows) -> dict[tuple[str, str], list[str]]:
    """The models among ``rows`` (``(agent, estimator)`` keys) by training folder and pose
    source, in order."""
    groups: dict[tuple[str, str], list[str]] = {}
    for agent, estimator in rows:
        group = training_group(agent)
        if group is not None:
            groups.setdefault((group, estimator), []).append(agent)
    return dict(sorted(groups.items()))


def aggregate_runs(
    scores: dict[tuple[str, str], dict[int, dict]], own_sources: dict[str, str] | None = None
) -> list[dict]:
    """Per training folder and pose source: IQM of success and SPL over its models' episodes
    on the test worlds every model finished, with two-level bootstrap intervals; where the
    follower drove the same pose source, each model's success paired with the follower's on
    the worlds both finished (Newcombe's interval) and the IQM's ratio to the follower's
    rate. ``own_sources`` (model -> the pose source it was trained on) adds ``trained_on``."""
    aggregates = []
    for (group, estimator), runs in training_groups(scores).items():
        worlds = sorted(set.intersection(*(set(scores[run, estimator]) for run in runs)))
        if not worlds:
            continue
        row = {
            "agent": group,
            "estimator": estimator,
            "trained_on": _trained_on(runs, own_sources),
            "models": runs,
            "runs": len(runs),
            "worlds": len(worlds),
        }
        for key in ("success", "spl"):
            matrix = [[float(scores[run, estimator][w][key]) for w in worlds] for run in runs]
            interval = seed_iqm(matrix)
            row[f"{key}_iqm"] = interval["estimate"]
            row[f"{key}_iqm_ci95"] = [interval["low"], interval["high"]]
            row[f"{key}_per_run"] = interval["per_run"]
        follower = scores.get((FOLLOWER, estimator))
        if follower:
            row |= _against_follower(follower, [scores[run, estimator] for run in runs], row)
        aggregates.append(row)
    return aggregates


def _trained_on(runs: list[str], own_sources: dict[str, str] | None) -> str | None:
    """The pose source the runs of one training folder were trained on (None if unknown)."""
    sources = {(own_sources or {}).get(run) for run in runs}
    return sources.pop() if len(sources) == 1 else None


def _against_follower(follower: dict[int, dict], runs: list[dict[int, dict]], row: dict) -> dict:
    """Each run's success paired with the follower's, and the IQM's ratio to its rate."""
    paired = [_paired_success(run, follower) for run in runs]
    rate = float(np.mean([bool(v["success"]) for v in follower.values()]))
    return {
        "follower_success_rate": rate,
        "ratio_to_follower": row["success_iqm"] / rate if rate else None,
        "paired_vs_follower": paired,
    }


def paired_across_sources(
    scores: dict[tuple[str, str], dict[int, dict]], own_sources: dict[str, str] | None = None
) -> list[dict]:
    """Whether learnt agents separate pose sources as the follower does: for every two
    training folders (or one folder on two pose sources) that drove on different pose
    sources, their runs paired seed by seed (the i-th run of each, in training-seed order),
    each pair's success compared on the test worlds both finished (Newcombe's interval).
    Each side names the pose source it drove on and, from ``own_sources``, the one it was
    trained on (protocol (b): the same; with ``--estimators``: maybe not)."""
    groups = list(training_groups(scores).items())
    pairs = []
    for ((first, source), runs), ((second, other), runs_b) in itertools.combinations(groups, 2):
        if source == other:
            continue
        per_run = [
            _paired_success(scores[run, source], scores[run_b, other])
            for run, run_b in zip(runs, runs_b, strict=False)
        ]
        pairs.append(
            {
                "first": {
                    "agent": first,
                    "estimator": source,
                    "trained_on": _trained_on(runs, own_sources),
                },
                "second": {
                    "agent": second,
                    "estimator": other,
                    "trained_on": _trained_on(runs_b, own_sources),
                },
                "success_difference_per_run": per_run,
                "runs_differing": sum(p["low"] > 0 or p["high"] < 0 for p in per_run),
            }
        )
    return pairs


def _paired_success(first: dict[int, dict], second: dict[int, dict]) -> dict:
    """Success of ``first`` minus ``second`` (scores by world) on the worlds both finished,
    with Newcombe's paired interval."""
    worlds = sorted(set(first) & set(second))
    return newcombe_paired(
        [bool(first[w]["success"]) for w in worlds], [bool(second[w]["success"]) for w in worlds]
    )
