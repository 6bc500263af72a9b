"""Renderings of a benchmark's results.json: the Markdown leaderboard and its figure."""

from __future__ import annotations

from pathlib import Path

from stsf_gym.agents import pretrained
from stsf_gym.experiments.benchmark.trained import SEED_FOLDERS
from stsf_gym.io import markdown_table, save_figure


def _label(row: dict) -> str:
    if not row["agent"].endswith(".zip"):  # an agent by name drives on every pose source
        return (
            row["estimator"]
            if row["agent"] == "follower"
            else f"{row['agent']} / {row['estimator']}"
        )
    return f"{agent_name(row['agent'])} / {row['estimator']}"


def agent_name(agent: str) -> str:
    """``follower``; a training folder by its name (``ppo-stsf``); a model by its training
    folder's name, with its seed folder (``ppo-stsf/seed-0``); a shipped agent's seed by its
    suite, name and seed (``corridor/dagger-truth/seed-0``); any other file by its stem. The
    JSON keeps the whole path."""
    path = Path(agent)
    if path.suffix != ".zip":
        return path.name
    if path.name != "model.zip":  # a shipped agent's seed: its suite and name before the seed
        shipped = pretrained.shipped_name(path)
        return (
            path.stem
            if shipped is None
            else f"{shipped.removeprefix(pretrained.PREFIX)}/{path.stem}"
        )
    folder = path.parent
    return f"{folder.parent.name}/{folder.name}" if folder.match(SEED_FOLDERS) else folder.name


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
            "\n## Trained agents on their own pose sources, paired run by run (success "
            "difference, Newcombe 1998, method 10)\n\n"
        )
        text += markdown_table(
            [
                {
                    "first - second": f"{agent_name(p['first']['agent'])} on "
                    f"{p['first']['estimator']} - {agent_name(p['second']['agent'])} on "
                    f"{p['second']['estimator']}",
                    "per run (95 % CI)": "; ".join(
                        f"{d['difference']:+.2f} ({d['low']:+.2f} to {d['high']:+.2f})"
                        for d in p["success_difference_per_run"]
                    ),
                    "runs whose CI excludes 0": f"{p['runs_differing']} of "
                    f"{len(p['success_difference_per_run'])}",
                }
                for p in summary["trained_paired"]
            ]
        )
    if summary["paired"]:
        text += "\n## Paired differences in success (Newcombe 1998, method 10) and SPL\n\n"
        pairs = []
        for p in summary["paired"]:
            s, d = p["success_difference"], p["spl_difference"]
            pairs.append(
                {
                    "agent": agent_name(p["agent"]),
                    "first - second": f"{p['first']} - {p['second']}",
                    "success difference (95 % CI)": f"{s['difference']:+.3f} "
                    f"({s['low']:+.3f} to {s['high']:+.3f})",
                    "CI excludes 0": "yes" if p["success_differs"] else "no",
                    "only first / only second": f"{s['only_first']} / {s['only_second']}",
                    "SPL difference (95 % CI)": f"{d['difference']:+.3f} "
                    f"({d['low']:+.3f} to {d['high']:+.3f})",
                }
            )
        text += markdown_table(pairs)
    if summary["failed"]:
        text += "\n## Cells that failed to run\n\n" + markdown_table(
            [{"cell": str(f["cell"]), "error": f["error"]} for f in summary["failed"]]
        )
    return text


def _iqm(row: dict, key: str) -> str:
    low, high = row[f"{key}_iqm_ci95"]
    return f"{row[f'{key}_iqm']:.2f} ({low:.2f}-{high:.2f})"


def _stat(value: dict) -> str:
    if value["mean"] is None:
        return "-"
    return f"{value['mean']:.2f} ± {value['std']:.2f}"


def plot_leaderboard(summary: dict, path: str | Path) -> Path:
    """Success rate (Wilson 95 % intervals) and SPL (bootstrap 95 % intervals) per row, and
    the paired differences in success with their intervals."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = sorted(summary["rows"], key=lambda r: r["success_rate"]["mean"])
    labels = [_label(r) for r in rows]
    fig, axes = plt.subplots(1, 3, figsize=(15, 0.5 * max(len(rows), len(summary["paired"])) + 2))
    for ax, key, ci, title in (
        (axes[0], "success_rate", "success_ci95", "success rate (Wilson 95 % CI)"),
        (axes[1], "spl", "spl_ci95", "SPL (stratified bootstrap 95 % CI)"),
    ):
        means = [r[key]["mean"] for r in rows]
        errors = [
            [m - r[ci][0] for m, r in zip(means, rows, strict=True)],
            [r[ci][1] - m for m, r in zip(means, rows, strict=True)],
        ]
        ax.errorbar(means, range(len(rows)), xerr=errors, fmt="o", capsize=4)
        ax.set(yticks=range(len(rows)), yticklabels=labels, xlim=(-0.02, 1.02), title=title)
        ax.grid(alpha=0.3)
    pairs = summary["paired"]
    ax = axes[2]
    for i, p in enumerate(pairs):
        s = p["success_difference"]
        color = "tab:red" if p["success_differs"] else "tab:gray"
        ax.errorbar(
            s["difference"],
            i,
            xerr=[[s["difference"] - s["low"]], [s["high"] - s["difference"]]],
            fmt="o",
            capsize=4,
            color=color,
        )
    ax.axvline(0, color="k", lw=0.8)
    ax.set(
        yticks=range(len(pairs)),
        yticklabels=[f"{p['first']} - {p['second']}" for p in pairs],
        title="paired success difference (95 % CI)",
    )
    ax.grid(alpha=0.3)
    worlds, episodes = summary["worlds"], rows[0]["episodes"] if rows else 0
    fig.suptitle(
        f"Suite {summary['suite']}: declared arrival, {episodes} test worlds "
        f"{worlds['world_seeds'][0]}-{worlds['world_seeds'][1]}"
    )
    fig.tight_layout()
    return save_figure(fig, path)
