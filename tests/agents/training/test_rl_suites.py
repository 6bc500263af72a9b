"""RL on a benchmark suite: train worlds, evaluation on held-out val worlds, several training
seeds, and the benchmark's aggregate over them (IQM with a stratified bootstrap interval)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import ROOT

from stsf_gym.agents import pretrained
from stsf_gym.config_files import SUITE_DIR
from stsf_gym.envs.suite import load_suite
from stsf_gym.envs.worlds.generator_config import load_generator_config
from stsf_gym.experiments.benchmark.run import benchmark_cells
from stsf_gym.experiments.benchmark.trained import (
    DEFAULT_ESTIMATORS,
    agent_pose_sources,
    aggregate_runs,
    paired_across_sources,
)
from stsf_gym.validation import ConfigError


def test_train_val_and_test_worlds_are_disjoint():
    gen = load_generator_config()
    train, val, test = (set(gen.split_range(s)) for s in ("train", "val", "test"))
    assert not (train & val) and not (train & test) and not (val & test)
    with pytest.raises(
        ConfigError, match=r"splits val \[1000005, 1000007\] and test .* must not overlap"
    ):
        load_generator_config(
            splits={"train": [0, 10], "test": [1000000, 10000], "val": [1000005, 3]}
        )


def _scores(successes: list[list[int]], source: str = "stsf") -> dict:
    """Synthetic per-model scores: ``successes[run][world]``, trained on and driving ``source``."""
    return {
        (f"/runs/ppo-{source}/seed-{r}/model.zip", source): {
            w: {"success": bool(v), "spl": 0.8 * v} for w, v in enumerate(row)
        }
        for r, row in enumerate(successes)
    }


def test_aggregate_over_training_seeds():
    scores = _scores([[1, 1, 1, 1, 0, 0, 1, 1], [1, 0, 1, 1, 0, 0, 1, 0], [0, 0, 0, 0, 0, 0, 1, 0]])
    scores["follower", "stsf"] = {w: {"success": True, "spl": 1.0} for w in range(8)}
    (row,) = aggregate_runs(scores)  # the follower is not a training run
    assert row["agent"] == "/runs/ppo-stsf" and row["runs"] == 3 and row["worlds"] == 8
    assert row["success_per_run"] == pytest.approx([0.75, 0.5, 0.125])
    assert row["success_iqm"] == pytest.approx(np.mean([0.75, 0.5, 0.125]))  # 3 runs: no trim
    low, high = row["success_iqm_ci95"]
    assert 0 <= low < row["success_iqm"] < high <= 1


def test_agents_trained_on_two_pose_sources_are_paired_run_by_run_on_the_same_worlds():
    good = _scores([[1] * 12, [1] * 11 + [0]], "mcl")
    poor = _scores([[0] * 12, [1] * 11 + [0]], "odometry")
    (pair,) = paired_across_sources(good | poor)
    assert pair["first"]["estimator"] != pair["second"]["estimator"]
    first, second = pair["success_difference_per_run"]
    sign = 1 if pair["first"]["estimator"] == "mcl" else -1
    assert sign * first["difference"] == pytest.approx(1.0) and first["pairs"] == 12
    assert second["difference"] == 0.0 and second["low"] < 0 < second["high"]
    assert pair["runs_differing"] == 1  # seed 0 separates, seed 1 does not
    assert paired_across_sources(good) == []  # one pose source: nothing to pair


def test_in_protocol_b_the_follower_drives_the_learnt_agents_pose_sources():
    sources = agent_pose_sources("follower", None, ["mcl", "odometry", "mcl"])
    assert sources == ["mcl", "odometry"]  # each once, no other
    assert agent_pose_sources("follower", None, []) == list(DEFAULT_ESTIMATORS)  # scripts alone
    assert agent_pose_sources("follower", ["stsf"], ["mcl"]) == ["stsf"]  # protocol (a)


def test_a_benchmark_runs_world_by_world_so_a_cut_short_run_is_paired():
    shipped = "pretrained:sparse/dagger-stsf"
    cells = benchmark_cells(load_suite("sparse"), ["follower", shipped], None, [0, 1, 2])
    per_world = len(cells) // 3
    assert per_world == 1 + len(pretrained.models(shipped))  # the follower on STSF, each model
    for first in range(0, len(cells), per_world):
        assert {c["seed"] for c in cells[first : first + per_world]} == {first // per_world}
    assert {c["estimator"] for c in cells} == {"stsf"}


def test_the_iqm_is_over_runs_not_over_binary_episodes():
    # 4 runs x 10 worlds, 80 % success each: the IQM of the flattened 0/1 matrix would be 1.0
    scores = _scores([[1] * 8 + [0] * 2] * 4)
    (row,) = aggregate_runs(scores)
    assert row["success_iqm"] == pytest.approx(0.8)
    runs = _scores([[1] * 10, [1] * 10, [1] * 9 + [0], [0] * 10])  # IQM drops the best and worst
    (row,) = aggregate_runs(runs)
    assert row["success_iqm"] == pytest.approx(np.mean([1.0, 0.9]))
    assert row["spl_iqm"] == pytest.approx(0.8 * row["success_iqm"])


def test_the_interval_carries_the_worlds_and_the_runs():
    (row,) = aggregate_runs(_scores([[1, 1, 1, 1]] * 3))  # nothing varies: a point
    assert row["success_iqm_ci95"] == pytest.approx([1.0, 1.0])
    (same,) = aggregate_runs(_scores([[1, 0, 1, 1]] * 3))  # identical runs: the worlds' spread
    (mixed,) = aggregate_runs(_scores([[1, 1, 1, 1], [1, 0, 1, 1], [0, 0, 1, 1]]))
    assert same["success_iqm_ci95"][0] < 0.75 < same["success_iqm_ci95"][1]
    width = [r["success_iqm_ci95"][1] - r["success_iqm_ci95"][0] for r in (same, mixed)]
    assert width[1] > 0 and width[0] > 0


@pytest.fixture(scope="module")
def short_suite(tmp_path_factory):
    """The corridor suite with 12 s episodes (a policy that never stops times out fast)."""
    suite = yaml.safe_load((SUITE_DIR / "corridor.yaml").read_text())
    suite["env"]["sim"] = {"max_episode_seconds": 12.0}
    path = tmp_path_factory.mktemp("suite") / "short.yaml"
    path.write_text(yaml.safe_dump(suite))
    return path


@pytest.mark.slow
def test_train_on_a_suite_with_seeds_then_benchmark_the_folder(short_suite, tmp_path):
    from stsf_gym.agents.training.train import train
    from stsf_gym.experiments.benchmark.run import benchmark

    out = tmp_path / "ppo-odometry"
    small = {"n_steps": 32, "batch_size": 32, "eval_freq": 32, "n_eval_episodes": 1}
    small |= {"demonstrations.expert_episodes": 0, "train_env.sim.max_episode_seconds": 12.0}
    for seed in (0, 1):
        summary = train(
            "ppo",
            "odometry",
            out / f"seed-{seed}",
            32,
            seed,
            overrides=small,
            n_envs=1,
            progress_bar=False,
            suite=str(short_suite),
        )
        assert summary["world"] == "generated:train"
        assert summary["evaluation_world"] == "generated:val"  # never the benchmark's test
        assert summary["env"]["task"]["protocol"] == "declare"  # the suite's task
        assert summary["env"]["task"]["start_along"] == 1.0  # the hyper-parameters' starts
        assert summary["env"]["sim"]["max_episode_seconds"] == 12.0  # the suite over them
    models = {str((out / f"seed-{s}" / "model.zip").resolve()) for s in (0, 1)}
    # protocol (a): trained on odometry, deployed on every pose source named, the follower too
    deployed = benchmark(
        tmp_path / "deployed", str(short_suite), [str(out), "follower"], ["stsf"], 1
    )
    rows = {(r["agent"], r["estimator"]) for r in deployed["rows"]}
    assert rows == {("follower", "stsf")} | {(m, "stsf") for m in models}
    (against,) = deployed["trained"]  # each run paired with the follower on the same world
    assert against["trained_on"] == "odometry" and against["models"] == sorted(models)
    report = (tmp_path / "deployed" / "leaderboard.md").read_text()
    assert "**ppo-odometry** (trained on odometry) on stsf, 2 training seeds" in report
    assert "| ppo-odometry/seed-1 | stsf |" in report
    assert [p["pairs"] for p in against["paired_vs_follower"]] == [1, 1]
    assert against["follower_success_rate"] in (0.0, 1.0)
    # protocol (b): no pose source named, each learnt agent drives on its own
    result = benchmark(tmp_path / "bench", str(short_suite), [str(out)], None, 2, workers=1)
    agents = {(r["agent"], r["estimator"]) for r in result["rows"]}
    assert agents == {(m, "odometry") for m in models}  # own source
    (trained,) = result["trained"]
    assert result["trained_paired"] == []  # one training folder: one pose source
    assert trained["agent"] == str(out.resolve()) and trained["runs"] == 2
    assert trained["worlds"] == 2 and len(trained["success_per_run"]) == 2
    saved = json.loads((tmp_path / "bench" / "results.json").read_text())
    assert saved["trained"] == json.loads(json.dumps(result["trained"]))
    assert (
        "Trained agents over their training seeds"
        in (tmp_path / "bench" / "leaderboard.md").read_text()
    )


def _seed_aggregate(results: Path, *options: str) -> str:
    """What ``benchmarks/seed_aggregate.py`` prints for a committed ``results.json``."""
    script = ROOT / "benchmarks/seed_aggregate.py"
    done = subprocess.run(
        [sys.executable, str(script), str(results), *options],
        capture_output=True,
        text=True,
        check=True,
    )
    return done.stdout


def test_seed_aggregate_recomputes_a_committed_benchmark():
    """``benchmarks/seed_aggregate.py`` on the learner's committed results: the benchmark's own
    IQM, and each seed paired with the follower on all 100 worlds."""
    results = ROOT / "benchmarks/results/learner-corridor/benchmark-truth-results.json"
    (entry,) = json.loads(_seed_aggregate(results, "--json"))
    (saved,) = json.loads(results.read_text())["trained"]
    assert entry["success_iqm"] == pytest.approx(saved["success_iqm"])
    assert entry["success_per_run"] == pytest.approx(saved["success_per_run"])
    assert [p["pairs"] for p in entry["paired_vs_follower"]] == [100, 100, 100]
    assert entry["follower_success_rate"] == 1.0


def test_seed_aggregate_prints_a_pose_source_the_follower_never_completed():
    """On protocol (b)'s committed results the follower completes no odometry route: the
    ratio to it is undefined, printed as '-', and every other row still printed."""
    results = ROOT / "benchmarks/results/learner-sparse/protocol-b/results.json"
    printed = _seed_aggregate(results)
    assert "follower 0.000; ratio -" in printed
    assert printed.count("success IQM over") == len(json.loads(results.read_text())["trained"])
