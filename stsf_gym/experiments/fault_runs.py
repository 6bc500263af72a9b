"""``stsf-gym evaluate --faults FILE...``: every fault set on every estimator, and the recovery.

A fault file holds a ``faults:`` list (:mod:`stsf_gym.envs.fault_spec`) and nothing else; its file
stem names the fault set. Each episode runs with the set's faults added to the env settings. The
table (``results.md``, ``results.json``) has one row per fault set and estimator:

- success rate and collisions, final and max position error;
- ``valid``: episodes whose estimate was finite and whose covariance was positive definite at
  every step;
- recovery, measured from the end of the set's last fault that ends (a removed landmark stays
  removed): the estimate has *recovered* when its position error is back under
  ``max(RECOVERY_FLOOR, 2 x its pre-fault level)`` (the mean error over the
  :data:`PRE_FAULT_SECONDS` before the first fault starts) for good, up to the episode's end;
  the *recovery distance* is the distance driven from the fault's end until then (0 when the
  error never left that bound), and *error after recovery* the mean error from then on. A set
  whose faults all last to the episode's end has no recovery.

Errors are recorded at every control step, so a recovery distance is known to one step of
driving (1.2 cm at the nominal speed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stsf_gym.envs.config import load_config, read_yaml
from stsf_gym.envs.fault_spec import fault_span
from stsf_gym.episode_env import estimator_options
from stsf_gym.experiments.episodes import (
    EpisodeResult,
    EpisodeSpec,
    run_episodes,
    specs_config,
)
from stsf_gym.experiments.plotting.maps import plot_errors
from stsf_gym.experiments.reports import write_report
from stsf_gym.io import markdown_table
from stsf_gym.results import SCHEMA_VERSION, rendered, stat
from stsf_gym.validation import ConfigError

RECOVERY_FLOOR = 0.10  # m: an error under this counts as recovered whatever it was before
PRE_FAULT_SECONDS = 10.0  # s of simulated time before the first fault: the pre-fault level


def load_fault_set(path: str | Path, world: str, env: dict) -> tuple[str, list[dict]]:
    """The name and ``faults`` list of a fault file, checked against the env it will run in."""
    path = Path(path)
    data = read_yaml(path)
    if set(data) != {"faults"} or not isinstance(data["faults"], list) or not data["faults"]:
        raise ConfigError(f"{path}: a fault file holds one key, a non-empty 'faults:' list")
    try:
        load_config({**env, "faults": data["faults"]}, world=world)
    except ConfigError as err:
        raise ConfigError(f"{path}: {err}") from err
    return path.stem, data["faults"]


def evaluate_faults(
    out: str | Path,
    estimators: list[str],
    seeds: int,
    seed: int,
    world: str,
    agent: str,
    workers: int,
    env: dict,
    fault_files: list[str | Path],
    backend: str = "local",
    address: str | None = None,
) -> tuple[dict, dict[str, list[EpisodeResult]]]:
    """Run ``seeds`` episodes per fault set and estimator; write the table and error plots.

    Returns the summary (as in results.json) and the episodes by ``"<fault set>/<estimator>"``.
    """
    out = Path(out)
    fault_sets = dict(load_fault_set(path, world, env) for path in fault_files)
    if len(fault_sets) != len(fault_files):
        raise ConfigError("fault files must have different names (their stems name the sets)")
    rows, runs, figures, configs = [], {}, [], {}
    for name, faults in fault_sets.items():
        spans = fault_span(load_config({**env, "faults": faults}, world=world).faults)
        specs = [
            EpisodeSpec(world, e, s, agent, {**env, "faults": faults}, estimator_options(e))
            for e in estimators
            for s in range(seed, seed + seeds)
        ]
        folder, desc = out / "episodes" / name, f"faults {name}"
        results = run_episodes(specs, folder, workers, desc, backend=backend, address=address)
        configs[name] = specs_config(specs)
        by_estimator = {e: [r for r in results if r.spec["estimator"] == e] for e in estimators}
        for estimator, episodes in by_estimator.items():
            rows.append(summarise_faults(name, estimator, episodes, *spans))
            runs[f"{name}/{estimator}"] = episodes
        figures.append(str(plot_errors(by_estimator, out / f"errors-{name}.png")))
    summary = {
        "schema_version": SCHEMA_VERSION,
        "world": world,
        "agent": agent,
        "seeds": [seed, seed + seeds - 1],
        "recovery_floor_m": RECOVERY_FLOOR,
        "rows": rows,
    }
    table = markdown_table([rendered(row, headers=HEADERS) for row in rows])
    write_report(
        out,
        summary,
        f"Fault runs: {agent} on {world}",
        table,
        config=configs,
        seeds=range(seed, seed + seeds),
    )
    summary["figures"] = figures
    return summary, runs


def recovery(episode: EpisodeResult, start: float, end: float | None) -> dict:
    """Pre-fault error, bound, and (for a fault that ends) whether, how far and how well the
    estimate recovered after ``end`` (see the module docstring)."""
    times, errors = np.asarray(episode.times), np.asarray(episode.errors)
    before = errors[(times < start) & (times >= start - PRE_FAULT_SECONDS)]
    pre_fault = float(before.mean()) if len(before) else 0.0
    result = {"pre_fault": pre_fault, "bound": max(RECOVERY_FLOOR, 2 * pre_fault)}
    if end is None:
        return result
    after = np.flatnonzero(times >= end - 1e-9)
    out = after[errors[after] > result["bound"]]
    back = out[-1] + 1 if len(out) else after[0] if len(after) else len(errors)
    result["recovered"] = bool(back < len(errors))
    if result["recovered"]:
        travelled = np.asarray(episode.travelled)
        at_end = float(np.interp(end, times, travelled))
        result["distance"] = max(0.0, float(travelled[back]) - at_end) if len(out) else 0.0
        result["error_after"] = float(errors[back:].mean())
    return result


#: Table headers of the fault rows' own keys (the rest: :data:`stsf_gym.results.METRICS`).
HEADERS = {
    "fault_set": "fault set",
    "valid_rate": "valid (finite, PD)",
    "pre_fault_error_m": "pre-fault error (m)",
    "recovered_rate": "recovered",
    "recovery_distance_m": "recovery distance (m)",
    "max_recovery_distance_m": "max recovery distance (m)",
    "error_after_recovery_m": "error after recovery (m)",
}


def summarise_faults(
    fault_set: str, estimator: str, episodes: list[EpisodeResult], start: float, end
) -> dict:
    """One results row: a fault set on an estimator over its episodes (numbers only)."""
    recoveries = [recovery(e, start, end) for e in episodes]
    back = [r for r in recoveries if r.get("recovered")]
    return {
        "fault_set": fault_set,
        "estimator": estimator,
        "episodes": len(episodes),
        "seeds": [e.spec["seed"] for e in episodes],
        "success_rate": stat(e.outcome == "goal" for e in episodes),
        "collision_rate": stat(e.outcome == "collision" for e in episodes),
        "valid_rate": stat(e.finite and e.min_cov_eigenvalue > 0 for e in episodes),
        "final_error_m": stat(float(e.errors[-1]) for e in episodes),
        "max_error_m": stat(float(np.max(e.errors)) for e in episodes),
        "pre_fault_error_m": stat(r["pre_fault"] for r in recoveries),
        "recovered_rate": stat(None if end is None else r["recovered"] for r in recoveries),
        "recovery_distance_m": stat(r["distance"] for r in back),
        "max_recovery_distance_m": max((r["distance"] for r in back), default=None),
        "error_after_recovery_m": stat(r["error_after"] for r in back),
        "relocalised": stat(e.relocalised for e in episodes),
    }
