"""A results file's rows as Markdown tables people read: a headline table (the pose source,
its outcome rates as means, its errors as mean ± std: 80 columns), then detail tables by
theme, each led by the pose source, so every column of the rows is somewhere."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from stsf_gym.io import markdown_table
from stsf_gym.results import is_stat, rendered

HEADLINE = [
    "estimator",
    "success_rate",
    "collision_rate",
    "ate_rmse_m",
    "final_error_m",
]
RATES = ("success_rate", "collision_rate")  # shown as their means in the headline
#: The detail tables: title and the keys they show (after the pose source).
DETAILS: dict[str, list[str]] = {
    "Outcomes": ["episodes", "time_limit_rate", "distance_before_failure_m"],
    "Localization": ["floor_ate_m", "ate_vs_floor", "rpe_trans_m_per_m", "rpe_rot_deg_per_m"],
    "Error along the route": ["max_error_m", "rms_heading_error_deg", "path_error_rms_m"],
    "Landmarks": ["match_rate", "landmark_in_view"],
    "NEES": ["nees_mean", "nees_bounds", "nees_in_bounds", "nees_verdict"],
    "NEES over time": ["nees_time_average", "nees_time_bounds", "nees_effective_steps"],
    "NIS": ["nis_mean", "nis_bounds", "nis_in_bounds"],
    "Cost": ["ms_per_step"],
}
NOT_SHOWN = {"seeds", "agent"}  # the seeds are in the JSON; one agent is in the title


def results_tables(rows: Sequence[Mapping], headers: Mapping[str, str] | None = None) -> str:
    """The headline table, then ``## <title>`` detail tables (:data:`DETAILS`, and ``Other``
    for keys of the rows no table lists); an agent column leads when the rows' agents differ."""
    if not rows:
        return markdown_table([])
    lead = ["agent", "estimator"] if len({row.get("agent") for row in rows}) > 1 else ["estimator"]
    listed = set(HEADLINE) | {key for keys in DETAILS.values() for key in keys} | NOT_SHOWN
    other = [key for key in rows[0] if key not in listed]
    means = [{**row, **{k: row[k]["mean"] for k in RATES if is_stat(row.get(k))}} for row in rows]
    tables = [markdown_table([rendered(row, lead + HEADLINE[1:], headers) for row in means])]
    for title, keys in {**DETAILS, "Other": other}.items():
        present = [key for key in keys if any(key in row for row in rows)]
        if present:
            table = markdown_table([rendered(row, lead + present, headers) for row in rows])
            tables.append(f"## {title}\n\n{table}")
    return "\n".join(tables)
