"""The results schema: every ``results.json`` row holds numbers; tables are renderings of it.

A metric over episodes (or seeds, or cells) is a :func:`stat`: ``{"mean", "std", "count",
"values"}`` with the per-episode values in run order (``mean``/``std`` are ``null`` when no
episode has a value, e.g. the distance before failure when none failed). Single numbers
(bounds, fractions) stay plain numbers. The names of the metrics and the version are fixed
here and documented in ``docs/results_schema.md``; :func:`render` turns a row into the strings
of the Markdown and terminal tables.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

#: Bumped when a key changes meaning or shape (``schema_version`` in every results.json).
SCHEMA_VERSION = 1

#: Metric keys and the unit or meaning shown in table headers.
METRICS: dict[str, str] = {
    "success_rate": "success rate",
    "collision_rate": "collision rate",
    "time_limit_rate": "time limit rate",
    "distance_before_failure_m": "distance before failure or time limit (m)",
    "ate_rmse_m": "ATE RMSE (m)",
    "floor_ate_m": "floor ATE (m)",
    "ate_vs_floor": "ATE / floor",
    "rpe_trans_m_per_m": "RPE trans (m/m)",
    "rpe_rot_deg_per_m": "RPE rot (deg/m)",
    "final_error_m": "final error (m)",
    "max_error_m": "max error (m)",
    "rms_heading_error_deg": "RMS heading error (deg)",
    "path_error_rms_m": "path error RMS (m)",
    "nees_mean": "NEES",
    "nees_bounds": "NEES 95% bounds (per step)",
    "nees_in_bounds": "NEES steps in bounds",
    "nees_time_average": "NEES time average",
    "nees_time_bounds": "its 95% bounds",
    "nees_effective_steps": "NEES independent steps",
    "nees_verdict": "NEES verdict",
    "nis_mean": "NIS",
    "nis_bounds": "NIS 95% bounds",
    "nis_in_bounds": "NIS in bounds",
    "match_rate": "landmark match rate",
    "landmark_in_view": "landmark in view",
    "ms_per_step": "ms per step",
}


#: The words of ``nees_verdict`` in tables (results.json keeps the number).
NEES_VERDICTS = {-1: "below: pessimistic", 0: "inside", 1: "above: over-confident"}


def finite_or_none(value: float) -> float | None:
    """``value`` as a float, or None for NaN or infinity (JSON has no NaN)."""
    return float(value) if math.isfinite(value) else None


def stat(values: Iterable[float | bool | None]) -> dict[str, Any]:
    """``{"mean", "std", "count", "values"}`` of ``values``; None and NaN are kept in
    ``values`` (as null) but not counted. Booleans count as 0/1, so their mean is a rate."""
    values = [None if v is None or (isinstance(v, float) and math.isnan(v)) else v for v in values]
    numbers = np.array([float(v) for v in values if v is not None])
    return {
        "mean": float(numbers.mean()) if numbers.size else None,
        "std": float(numbers.std()) if numbers.size else None,
        "count": int(numbers.size),
        "values": [None if v is None else float(v) for v in values],
    }


def stats(per_episode: list[Mapping[str, float | None]]) -> dict[str, dict]:
    """A :func:`stat` for every metric key of the per-episode dicts, in first-seen order."""
    keys = list(dict.fromkeys(key for metrics in per_episode for key in metrics))
    return {key: stat(metrics.get(key) for metrics in per_episode) for key in keys}


#: Row keys that hold labels (text) rather than measurements.
LABEL_KEYS = frozenset({"agent", "estimator", "fault_set", "world", "paper"})


def check_rows(rows: Iterable[Mapping[str, Any]], where: str = "rows") -> None:
    """Raise ValueError naming the first row entry that is not a number, null, a list of
    numbers, a stat or a mapping of stats (labels in :data:`LABEL_KEYS` excepted)."""
    for i, row in enumerate(rows):
        for key, value in row.items():
            if key not in LABEL_KEYS and not _numeric(value):
                raise ValueError(f"{where}[{i}].{key} is not numeric: {value!r}")


def _numeric(value: Any) -> bool:
    if value is None or _number(value) or isinstance(value, bool):
        return value is None or isinstance(value, bool) or math.isfinite(value)
    if isinstance(value, list | tuple):
        return all(_numeric(v) for v in value)
    if isinstance(value, Mapping):
        return all(_numeric(v) for v in value.values())
    return False


def is_stat(value: Any) -> bool:
    """True when ``value`` is a statistic of the schema (``{mean, std, count, ...}``)."""
    return isinstance(value, Mapping) and {"mean", "std", "count"} <= set(value)


def render(value: Any, digits: int = 3) -> str:
    """A table cell: ``mean ± std`` for a stat (``-`` without values), ``lo-hi`` for bounds,
    ``stage 0.12, ...`` for per-stage stats, numbers with ``digits`` decimals."""
    if is_stat(value):
        if value["mean"] is None:
            return "-"
        if value["count"] == 1 or value["std"] == 0:
            return f"{value['mean']:.{digits}f}"
        return f"{value['mean']:.{digits}f} ± {value['std']:.{digits}f}"
    if isinstance(value, Mapping):
        return ", ".join(f"{k} {render(v, 2)}" for k, v in value.items()) or "-"
    if isinstance(value, list | tuple) and len(value) == 2 and all(_number(v) for v in value):
        return f"{value[0]:.2f}-{value[1]:.2f}"
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def rendered(
    row: Mapping[str, Any],
    columns: Iterable[str] | None = None,
    headers: Mapping[str, str] | None = None,
) -> dict[str, str]:
    """``row`` as table cells (``columns`` only, all but the seeds by default) under readable
    headers: ``headers``, then :data:`METRICS`, else the key itself."""
    keys = list(columns) if columns is not None else [k for k in row if k != "seeds"]
    names = {**METRICS, **(headers or {})}
    return {names.get(key, key): _cell(key, row.get(key)) for key in keys}


def _cell(key: str, value: Any) -> str:
    if key == "nees_verdict" and value in NEES_VERDICTS:
        return NEES_VERDICTS[value]
    return render(value)


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)
