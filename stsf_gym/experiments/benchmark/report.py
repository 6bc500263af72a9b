"""The Markdown leaderboard of a benchmark's results.json (``leaderboard.md``, printed in the
terminal too): every row named by its agent, the learnt agents beside the follower, the
paired differences, what each agent does near its goals."""

from __future__ import annotations

from stsf_gym.experiments.benchmark.against_follower import against_follower_markdown
from stsf_gym.experiments.benchmark.references import references_markdown
from stsf_gym.experiments.benchmark.small_samples import interval, noted
from stsf_gym.experiments.benchmark.trained import agent_name
from stsf_gym.io import markdown_table


def leaderboard_markdown(summary: dict) -> str:
    """The leaderboard (best success first), the paired differences, the worlds."""
    rows = sorted(summary["rows"], key=lambda r: -r["success_rate"]["mean"])
    worlds = summary["worlds"]
    text = (
        f"# Leaderboard: suite `{summary['suite']}`, declared arrival\n\n"
        f"Test worlds {worlds['world_seeds'][0]}-{worlds['world_seeds'][1]} "
        f"({rows[0]['episodes'] if rows else 0} episodes per row, the same worlds and seeds for "
        f"every row); success: a declared stop within {summary['goal_radius_m']} m of every "
        f"goal in order. Measured landmark coverage {worlds['coverage']['mean']:.2f} "
        f"(range {min(worlds['coverage']['values']):.2f}-{max(worlds['coverage']['values']):.2f}, "
        f"configured {worlds['coverage_configured'][0]}-{worlds['coverage_configured'][1]}), "
        f"longest stretch with no board in view {worlds['longest_dark_m']['mean']:.1f} m on "
        f"average, {worlds['goals']['mean']:.2f} goals and {worlds['path_length_m']['mean']:.1f} m "
        "of path per world.\n\n"
    )
    table = []
    for r in rows:
        f = r["failures"]
        table.append(
            {
                "agent": agent_name(r["agent"]),
                "pose source": r["estimator"],
                "success (95 % CI)": f"{r['success_rate']['mean']:.2f} "
                f"({r['success_ci95'][0]:.2f}-{r['success_ci95'][1]:.2f})",
                "SPL (95 % CI)": f"{r['spl']['mean']:.3f} "
                f"({r['spl_ci95'][0]:.3f}-{r['spl_ci95'][1]:.3f})",
                "distance at stops (m)": _stat(r["stop_distance_m"]),
                "goals reached": f"{r['goals_reached_share']['mean']:.2f}",
                "missed near / far": f"{f['missed_near']} / {f['missed_far']}",
                "collisions": f["collision"],
                "time-outs": f["time"],
                "ATE RMSE (m)": _stat(r["ate_rmse_m"]),
            }
        )
    text += markdown_table(table)
    text += against_follower_markdown(summary)
    if summary.get("trained"):
        text += (
            "\n## Trained agents over their training seeds (IQM, 95 % stratified bootstrap; "
            "Agarwal et al. 2021)\n\n"
        )
        text += markdown_table(
            [
                {
                    "agent": agent_name(t["agent"]),
                    "pose source": t["estimator"],
                    "runs x worlds": f"{t['runs']} x {t['worlds']}",
                    "success IQM (95 % CI)": _iqm(t, "success"),
                    "success per run": ", ".join(f"{v:.2f}" for v in t["success_per_run"]),
                    "SPL IQM (95 % CI)": _iqm(t, "spl"),
                }
                for t in summary["trained"]
            ]
        )
    if summary.get("trained_paired"):
        text += (
            f"\n## Trained agents {_where(summary['trained_paired'])}, paired run by run "
            "(success difference, Newcombe 1998, method 10)\n\n"
        )
        runs = [d for p in summary["trained_paired"] for d in p["success_difference_per_run"]]
        table = [
            {
                "first - second": f"{_side(p['first'])} - {_side(p['second'])}",
                "per run (95 % CI)": "; ".join(
                    interval(d, d["pairs"]) for d in p["success_difference_per_run"]
                ),
                "runs whose CI excludes 0": f"{p['runs_differing']} of "
                f"{len(p['success_difference_per_run'])}",
            }
            for p in summary["trained_paired"]
        ]
        text += noted(markdown_table(table), min(d["pairs"] for d in runs))
    if summary["paired"]:
        text += "\n## Paired differences in success (Newcombe 1998, method 10) and SPL\n\n"
        pairs = []
        for p in summary["paired"]:
            s, d = p["success_difference"], p["spl_difference"]
            pairs.append(
                {
                    "agent": agent_name(p["agent"]),
                    "first - second": f"{p['first']} - {p['second']}",
                    "success difference (95 % CI)": interval(s, s["pairs"], 3),
                    "CI excludes 0": "yes" if p["success_differs"] else "no",
                    "only first / only second": f"{s['only_first']} / {s['only_second']}",
                    "SPL difference (95 % CI)": interval(d, s["pairs"], 3),
                }
            )
        text += noted(
            markdown_table(pairs), min(p["success_difference"]["pairs"] for p in summary["paired"])
        )
    if summary.get("against_references"):
        text += references_markdown(summary["against_references"])
    if summary.get("behaviour"):
        text += behaviour_markdown(summary["behaviour"])
    if summary["failed"]:
        text += "\n## Cells that failed to run\n\n" + markdown_table(
            [{"cell": str(f["cell"]), "error": f["error"]} for f in summary["failed"]]
        )
    return text


def behaviour_markdown(rows: list[dict]) -> str:
    """What each agent does near its goals (:mod:`.agent_behaviour`): means ± standard
    deviations, the stop measures over every declared stop, the rest over episodes."""
    table = [
        {
            "agent": agent_name(r["agent"]),
            "pose source": r["estimator"],
            "distance at stop (m)": _stat(r["stop_distance_m"]),
            "sigma at stop (m)": _stat(r["stop_sigma_m"]),
            "last metre (s)": _stat(r["approach_time_s"]),
            "speed, last metre (m/s)": _stat(r["approach_speed_mps"]),
            "off the route (m)": _stat(r["largest_path_distance_m"]),
            "board in view": _stat(r["boards_in_view_share"]),
            "collisions": f"{r['collision']['mean']:.2f}",
            "stops": r["stop_distance_m"]["count"],
        }
        for r in rows
    ]
    return (
        "\n## Near the goals: where each agent declares and how it gets there\n\n"
        "Per declared stop: its true distance to the goal, the estimate's position standard "
        "deviation there, the time from first coming within 1 m of the stop, the mean speed "
        "over the last metre driven; per episode: the largest distance from the route, the "
        "share of frames with a board in view, the share ending in a collision.\n\n"
        + markdown_table(table)
    )


def _where(pairs: list[dict]) -> str:
    """Where the paired agents drove: their own pose sources (protocol (b)), or those named by
    ``--estimators``, some not the one an agent was trained on (protocol (a))."""
    sides = [side for p in pairs for side in (p["first"], p["second"])]
    if all(side.get("trained_on") == side["estimator"] for side in sides):
        return "on their own pose sources"
    if any(side.get("trained_on") not in (None, side["estimator"]) for side in sides):
        return "on the pose sources named by --estimators (not all their own)"
    return "on different pose sources"  # results written before sides said what they knew


def _side(side: dict) -> str:
    trained = side.get("trained_on")
    own = "" if trained in (None, side["estimator"]) else f" (trained on {trained})"
    return f"{agent_name(side['agent'])} on {side['estimator']}{own}"


def _iqm(row: dict, key: str) -> str:
    low, high = row[f"{key}_iqm_ci95"]
    return f"{row[f'{key}_iqm']:.2f} ({low:.2f}-{high:.2f})"


def _stat(value: dict) -> str:
    if value["mean"] is None:
        return "-"
    return f"{value['mean']:.2f} ± {value['std']:.2f}"
