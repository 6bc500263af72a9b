"""benchmarks/learning_curves.py: IQM over seeds of val success and return at each
evaluation, for every stage a run logged, one figure per suite."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import load_script

from stsf_gym.io import write_json


def _script():
    return load_script("benchmarks/learning_curves.py")


def _run(
    folder: Path,
    seed: int,
    suite: str,
    rounds: list[list[int]],
    evals: list[list[int]],
    kept: int | None = None,
):
    """A run folder as the trainer leaves it: rounds (``kept``: the one the run kept), then
    evaluations of the reward stage."""
    folder.mkdir(parents=True)
    demonstrations = {} if kept is None else {"demonstrations": {"kept_round": kept}}
    write_json(folder / "train.json", {"suite": suite, "world": "generated:train"} | demonstrations)
    history = [
        {"round": i, "control_steps": 1000 * (i + 1), "wall_time_s": 60.0 * (i + 1) + seed,
         "val_success": sum(s) / len(s), "val_episodes": s, "val_returns": [5.0 * v for v in s]}
        for i, s in enumerate(rounds)
    ]  # fmt: skip
    if history:
        write_json(folder / "demonstrations.json", {"made_by": "x", "rounds": history})
    write_json(
        folder / "evaluations.json",
        [
            {"timesteps": 64 * (i + 1), "control_steps": 5000 * (i + 1), "wall_time_s": 600.0,
             "val_episodes": s, "val_returns": [5.0 * v - 1 for v in s]}
            for i, s in enumerate(evals)
        ],
    )  # fmt: skip


def test_curves_aggregate_seeds_per_evaluation_and_draw_one_figure_per_suite(tmp_path):
    script = _script()
    for seed, (first, last) in enumerate([([0, 1], [1, 1]), ([0, 0], [1, 0]), ([1, 0], [1, 1])]):
        _run(tmp_path / "tuned" / f"seed-{seed}", seed, "sparse", [first], [last])
    _run(tmp_path / "plain", 0, "corridor", [], [[0, 0], [0, 1]])
    curves = {
        "fine-tuned": script.curve(tmp_path / "tuned"),
        "plain": script.curve(tmp_path / "plain"),
    }
    tuned = curves["fine-tuned"]
    assert tuned["suite"] == "sparse" and [p["stage"] for p in tuned["points"]] == [
        "demonstrations",
        "reward",
    ]
    first, last = tuned["points"]
    assert first["seeds"] == 3 and first["success_per_seed"] == [0.5, 0.0, 0.5]
    assert first["success_ci95"][0] <= first["success_iqm"] <= first["success_ci95"][1]
    assert last["success_iqm"] > first["success_iqm"] and last["control_steps"] == 5000
    assert last["return_iqm"] == pytest.approx(last["success_iqm"] * 5 - 1)  # a linear map
    for suite in ("sparse", "corridor"):
        assert script.plot(curves, suite, tmp_path / f"{suite}.png").stat().st_size > 0
    assert "| plain | corridor | reward | 1 |" in script.table(curves)


def test_the_reward_stage_starts_from_the_round_it_kept(tmp_path):
    script = _script()
    _run(tmp_path / "tuned", 0, "sparse", [[0, 0], [1, 1], [0, 1]], [[1, 0]], kept=1)
    points = script.curve(tmp_path / "tuned")["points"]
    assert [p["stage"] for p in points] == ["demonstrations"] * 3 + ["reward"] * 2
    start = points[3]
    assert start["success_iqm"] == 1.0  # the kept round's, not the last round's 0.5
    assert start["control_steps"] == points[2]["control_steps"]  # where the stage begins
