"""The benchmark's report on small synthetic results: each learnt agent beside the follower on
the same pose source in words and a table, agent names on every row and in the figure, the
paired section titled by where the agents drove, and tables that fit 80 columns."""

from __future__ import annotations

import os

import pytest
from rich.console import Console

from stsf_gym.agents import pretrained
from stsf_gym.envs.suite import load_suite
from stsf_gym.experiments.benchmark.figure import paired_rows, plot_leaderboard, row_label
from stsf_gym.experiments.benchmark.intervals import newcombe_paired
from stsf_gym.experiments.benchmark.report import leaderboard_markdown
from stsf_gym.experiments.benchmark.run import summarise_benchmark
from stsf_gym.experiments.benchmark.small_samples import MARK, MIN_PAIRED_WORLDS
from stsf_gym.experiments.benchmark.trained import agent_name
from stsf_gym.terminal_table import NAME_WIDTH, print_markdown

WORLDS = 12
SEED_0 = "/runs/ppo-truth/seed-0/model.zip"
SEED_1 = "/runs/ppo-truth/seed-1/model.zip"
ON_STSF = "/runs/ppo-stsf/seed-0/model.zip"  # trained on STSF's estimate
FINE_0, FINE_1 = (f"/runs/fine-stsf/seed-{s}/model.zip" for s in (0, 1))  # fine-tuned on STSF
CLONE_0, CLONE_1 = (f"/runs/fine-stsf/seed-{s}/finetune/clone.zip" for s in (0, 1))
#: Which worlds each (agent, pose source) succeeds on: the follower on all of the true pose's,
#: seed 0 of the learnt agent on two, seed 1 on all but one.
SUCCEEDS = {
    ("follower", "truth"): set(range(WORLDS)),
    ("follower", "stsf"): set(range(0, WORLDS, 2)),
    (SEED_0, "truth"): {0, 1},
    (SEED_1, "truth"): set(range(1, WORLDS)),
    (SEED_0, "stsf"): {0},
    (SEED_1, "stsf"): {0, 2},
    (ON_STSF, "stsf"): {0, 2, 4},
    ("cautious-follower", "stsf"): set(range(0, WORLDS, 3)),
    (FINE_0, "stsf"): set(range(0, WORLDS, 2)) | {1},
    (FINE_1, "stsf"): set(range(0, WORLDS, 2)) | {3, 5},
    (CLONE_0, "stsf"): set(range(0, WORLDS, 2)),  # each clone one or two worlds short of its run
    (CLONE_1, "stsf"): set(range(0, WORLDS, 2)),
}


def _result(success: bool) -> dict:
    stop = {"true_distance_m": 0.1 if success else 2.0, "success": success}
    behaviour = {  # a careful stop where it succeeds, a hurried one where it misses
        "stop_distance_m": [stop["true_distance_m"]],
        "stop_sigma_m": [0.05 if success else 0.4],
        "approach_time_s": [12.0 if success else 6.0],
        "approach_speed_mps": [0.08 if success else 0.17],
        "largest_path_distance_m": 0.2,
        "boards_in_view_share": 0.5,
        "collision": False,
        "success": success,
    }
    return {
        "outcome": "goal" if success else "missed",
        "distance": 12.0,
        "metrics": {"ate_rmse_m": 0.1},
        "navigation": {"goals": 1, "geodesic_length_m": 10.0, "stops": [stop]},
        "behaviour": behaviour,
    }


def _summary(keys, estimator_name: dict | None = None) -> dict:
    """summarise_benchmark over hand-made cells: ``keys`` are (agent, pose source)."""
    rename = estimator_name or {}
    cells, results = [], []
    for agent, source in keys:
        for seed in range(WORLDS):
            name = rename.get(source, source)
            cells.append({"agent": agent, "estimator": name, "seed": seed, "values": {}})
            results.append(_result(seed in SUCCEEDS[agent, source]))
    own = {SEED_0: "truth", SEED_1: "truth", ON_STSF: "stsf", FINE_0: "stsf", FINE_1: "stsf"}
    own |= {CLONE_0: "stsf", CLONE_1: "stsf"}
    summary = summarise_benchmark(load_suite("corridor"), cells, results, own)
    summary["worlds"] = {
        "world_seeds": [1000, 1000 + WORLDS - 1],
        "coverage_configured": [1, 1],
        "coverage": {"mean": 1.0, "values": [1.0]},
        "longest_dark_m": {"mean": 0.0},
        "goals": {"mean": 1.0},
        "path_length_m": {"mean": 10.0},
    }
    return summary


OWN = [("follower", "truth"), (SEED_0, "truth"), (SEED_1, "truth")]


def _table(text: str, heading: str) -> list[list[str]]:
    """The body rows of the first Markdown table after ``heading``."""
    lines = text[text.index(heading) :].splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("|"))
    rows = []
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip("|").split("|")])
    return rows


def _difference(first, second) -> dict:
    worlds = range(WORLDS)
    return newcombe_paired(
        [w in SUCCEEDS[first] for w in worlds], [w in SUCCEEDS[second] for w in worlds]
    )


def test_each_learnt_model_is_shown_beside_the_follower_with_its_paired_interval():
    text = leaderboard_markdown(_summary(OWN))
    assert "## Learnt agents beside the follower on the same pose source" in text
    assert "**ppo-truth** on truth, 2 training seeds" in text
    assert "1 of 2 below the follower, 0 above, 1 not told apart" in text
    rows = {row[0]: row for row in _table(text, "## Learnt agents beside")}
    assert set(rows) == {"ppo-truth/seed-0", "ppo-truth/seed-1"}
    for model, name in ((SEED_0, "ppo-truth/seed-0"), (SEED_1, "ppo-truth/seed-1")):
        d = _difference((model, "truth"), ("follower", "truth"))
        interval = f"{d['difference']:+.2f} ({d['low']:+.2f} to {d['high']:+.2f})"
        rate = len(SUCCEEDS[model, "truth"]) / WORLDS
        assert rows[name] == [name, "truth", f"{rate:.2f}", "1.00", interval, rows[name][5]]
    assert rows["ppo-truth/seed-0"][5] == "below" and rows["ppo-truth/seed-1"][5] == "level"


def test_what_each_agent_does_near_its_goals_is_summarised_beside_its_success():
    summary = _summary([("follower", "stsf"), (ON_STSF, "stsf")])
    rows = {(r["agent"], r["estimator"]): r for r in summary["rows"]}
    for near in summary["behaviour"]:
        row = rows[near["agent"], near["estimator"]]
        assert near["success"]["mean"] == row["success_rate"]["mean"]
        assert near["stop_distance_m"]["values"] == row["stop_distance_m"]["values"]
    follower = next(r for r in summary["behaviour"] if r["agent"] == "follower")
    # half its stops careful (0.05 m), half hurried (0.4 m)
    assert follower["stop_sigma_m"]["mean"] == pytest.approx(0.225)
    table = _table(leaderboard_markdown(summary), "## Near the goals")
    assert [line[:2] for line in table] == [["follower", "stsf"], [agent_name(ON_STSF), "stsf"]]
    sigma = follower["stop_sigma_m"]
    assert table[0][3] == f"{sigma['mean']:.2f} ± {sigma['std']:.2f}"
    assert table[1][-1] == str(WORLDS)  # one stop a world


def test_a_fine_tuned_folder_is_paired_with_its_clones_and_the_scripts_run_by_run():
    keys = [("follower", "stsf"), ("cautious-follower", "stsf")]
    keys += [(m, "stsf") for m in (FINE_0, FINE_1, CLONE_0, CLONE_1)]
    summary = _summary(keys)
    entries = {e["reference"]: e for e in summary["against_references"]}
    assert set(entries) == {"follower", "cautious-follower", "clone"}  # clones have none
    assert {e["agent"] for e in entries.values()} == {"/runs/fine-stsf"}
    clone = entries["clone"]
    assert clone["runs"] == 2 and clone["worlds"] == WORLDS
    # run 0 gains world 1 over its clone, run 1 worlds 3 and 5: IQM of two runs is their mean
    assert clone["success_iqm_difference"]["difference"] == pytest.approx(1.5 / WORLDS)
    assert [p["only_first"] for p in clone["paired_per_run"]] == [1, 2]
    assert [p["only_second"] for p in clone["paired_per_run"]] == [0, 0]
    follower = entries["follower"]["paired_per_run"]
    assert follower[1] == _difference((FINE_1, "stsf"), ("follower", "stsf"))
    table = _table(leaderboard_markdown(summary), "## Learnt agents against their references")
    assert [row[2] for row in table] == ["follower", "cautious-follower", "clone"]
    assert table[2][0] == "fine-stsf" and table[2][-1] == str(WORLDS)


def test_every_row_names_its_agent():
    text = leaderboard_markdown(_summary(OWN))
    agents = {row[0] for row in _table(text, "| agent | pose source | success (95 % CI)")}
    assert agents == {"follower", "ppo-truth/seed-0", "ppo-truth/seed-1"}
    shipped = pretrained.MODELS / "corridor" / "ppo-truth" / "seed-2.zip"
    assert agent_name(str(shipped)) == "ppo-truth/seed-2"  # not a bare seed-2
    relative = "agents/pretrained/trained-models/sparse/ppo-mcl/seed-0.zip"
    assert agent_name(relative) == "ppo-mcl/seed-0"


def test_without_the_follower_on_that_pose_source_the_report_says_how_to_get_it():
    text = leaderboard_markdown(_summary([(SEED_0, "truth"), (SEED_1, "truth")]))
    assert "the follower did not drive on truth in this run" in text


@pytest.mark.parametrize(
    ("keys", "title", "pair"),
    [
        (  # protocol (b): each learnt agent on the pose source it was trained on
            [(SEED_0, "truth"), (ON_STSF, "stsf")],
            "on their own pose sources",
            "ppo-stsf on stsf - ppo-truth on truth",
        ),
        (  # protocol (a): --estimators truth,stsf for an agent trained on the true pose
            [(SEED_0, "truth"), (SEED_1, "truth"), (SEED_0, "stsf"), (SEED_1, "stsf")],
            "on the pose sources named by --estimators (not all their own)",
            "ppo-truth on stsf (trained on truth) - ppo-truth on truth",
        ),
    ],
)
def test_the_paired_section_says_where_the_agents_drove(keys, title, pair):
    text = leaderboard_markdown(_summary(keys))
    heading = f"## Trained agents {title}, paired run by run"
    assert heading in text and text.count("## Trained agents on") == 1
    (row,) = _table(text, heading)
    assert row[0] == pair


def test_the_figure_names_the_agent_of_every_row(tmp_path):
    summary = _summary([*OWN, ("follower", "stsf")])
    assert sorted(row_label(row) for row in summary["rows"]) == [
        "follower / stsf",
        "follower / truth",
        "ppo-truth/seed-0 / truth",
        "ppo-truth/seed-1 / truth",
    ]
    labels = [label for label, _ in paired_rows(summary)]
    assert labels == [
        "follower: truth - stsf",
        "ppo-truth/seed-0 - follower, on truth",
        "ppo-truth/seed-1 - follower, on truth",
    ]
    assert plot_leaderboard(summary, tmp_path / "leaderboard.png").stat().st_size > 10_000


def test_terminal_tables_fit_80_columns_with_a_long_pose_source_name():
    long_name = "my_package.estimators:VeryLongEstimatorName"
    summary = _summary([*OWN, ("follower", "stsf")], {"stsf": long_name})
    console = Console(width=80, record=True, file=open(os.devnull, "w"))
    print_markdown(leaderboard_markdown(summary), console, "leaderboard.md")
    lines = console.export_text().splitlines()
    assert max(len(line.rstrip()) for line in lines) <= 80
    header = next(i for i, line in enumerate(lines) if line.startswith("agent"))
    assert "success" in " ".join(lines[header - 2 : header + 1])  # the column stayed
    assert not any(long_name in line for line in lines)  # wrapped, kept whole
    for part in ("my_package.", "estimators:", long_name.split(":")[1][:NAME_WIDTH]):
        assert any(line.startswith(part) or f" {part}" in line for line in lines), part


@pytest.mark.parametrize("worlds", [2, 6])
def test_intervals_from_too_few_worlds_are_marked_with_a_note(worlds):
    cells, results = [], []
    for source in ("truth", "stsf"):
        for seed in range(worlds):
            cells.append({"agent": "follower", "estimator": source, "seed": seed, "values": {}})
            results.append(_result(source == "truth"))
    summary = summarise_benchmark(load_suite("corridor"), cells, results, {})
    summary["worlds"] = _summary(OWN)["worlds"]
    text = leaderboard_markdown(summary)
    row = _table(text, "## Paired differences")[0]
    assert row[2].endswith(MARK) == (worlds < MIN_PAIRED_WORLDS)
    assert ("too few to separate anything" in text) == (worlds < MIN_PAIRED_WORLDS)
