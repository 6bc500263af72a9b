"""A saved result's own consistency: what a result file edited by hand (or by another tool)
breaks, checked before the cache reuses it (:func:`~stsf_gym.experiments.jobs.cache.
run_cached`). A result that fails is recomputed, and the run names it.

What the code never writes: a result that is not a mapping; a declared stop marked a success
farther from its goal than the task's radius (or a miss within it); an episode marked finite
whose estimates or covariances hold a NaN or an infinity; in a cell (the benchmark's, the
accuracy curve's), any number that is not finite (its metrics are numbers or null).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

#: m: rounding allowed between a stop's distance and the goal radius it was judged by
RADIUS_TOLERANCE = 1e-9


def episode_problem(result: Any, config: Mapping | None) -> str | None:
    """What is wrong with an episode's saved result (an ``EpisodeResult`` as a dict), or None."""
    if not isinstance(result, Mapping):
        return f"its result is a {type(result).__name__}, not a mapping"
    if result.get("finite"):
        for key in ("estimates", "covariances"):
            where = _non_finite(result.get(key), key)
            if where:
                return f"it is marked finite but {where}"
    return _stops_problem(result.get("stops") or [], config)


def cell_problem(result: Any, config: Mapping | None) -> str | None:
    """What is wrong with a cell's saved result, or None (a failure kept as a result is
    checked by nothing but its being a mapping)."""
    if not isinstance(result, Mapping):
        return f"its result is a {type(result).__name__}, not a mapping"
    if "error" in result:
        return None
    where = _non_finite(result, "result")
    if where:
        return where
    navigation = result.get("navigation")
    return _stops_problem(navigation.get("stops") or [], config) if navigation else None


def _non_finite(value: Any, path: str) -> str | None:
    """``"<path> holds nan"`` for the first non-finite number in ``value``, or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return f"{path} holds {value}"
    if isinstance(value, Mapping | list | tuple):
        items = value.items() if isinstance(value, Mapping) else enumerate(value)
        for key, item in items:
            found = _non_finite(item, f"{path}[{key!r}]")
            if found:
                return found
    return None


def _stops_problem(stops: list, config: Mapping | None) -> str | None:
    """A stop whose ``success`` disagrees with its distance and the goal radius of ``config``
    (the job's resolved configuration; nothing checked without one)."""
    radius = ((config or {}).get("env") or {}).get("task", {}).get("goal_radius")
    if radius is None:
        return None
    for i, stop in enumerate(stops):
        distance = stop.get("true_distance_m") if isinstance(stop, Mapping) else None
        if not isinstance(distance, int | float):
            return f"stops[{i}] is not a stop: {stop!r}"
        within = distance <= radius + RADIUS_TOLERANCE
        if bool(stop.get("success")) != within:
            said = "a success" if stop.get("success") else "a miss"
            return (
                f"stops[{i}] is marked {said} {distance:.3g} m from its goal "
                f"(goal radius {radius:g} m)"
            )
    return None
