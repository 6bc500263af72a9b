"""The demo answers the project's question: on its worlds the pose sources separate."""

from dataclasses import asdict

import pytest

from stsf_gym.envs.generated_env import episode_config
from stsf_gym.envs.suite import load_suite
from stsf_gym.experiments import demo
from stsf_gym.experiments.benchmark.intervals import newcombe_paired
from stsf_gym.experiments.benchmark.small_samples import MARK, MIN_PAIRED_WORLDS
from stsf_gym.experiments.demo import (
    DEMO_SOURCES,
    DEMO_SUITE,
    DEMO_WORLD,
    DEMO_WORLDS,
    demo_specs,
    headline,
    paragraph,
)
from stsf_gym.experiments.episodes import EpisodeSpec, run_episodes, run_job


def test_the_demo_runs_the_declared_arrival_task_on_the_same_worlds_for_each_source():
    specs = demo_specs(DEMO_WORLDS, 0)
    assert DEMO_WORLDS >= MIN_PAIRED_WORLDS  # enough worlds for a paired difference to show
    assert all(spec.env["task"]["protocol"] == "declare" for spec in specs)
    assert all(spec.env == load_suite(DEMO_SUITE).episode_env for spec in specs)
    for source in DEMO_SOURCES:
        assert [s.seed for s in specs if s.estimator == source] == list(range(DEMO_WORLDS))
    assert {"odometry", "stsf"} <= set(DEMO_SOURCES)


def test_the_demos_episodes_skip_the_floor_which_it_does_not_show(tmp_path, monkeypatch):
    short = {"sim": {"max_episode_seconds": 2.0}}
    job = asdict(EpisodeSpec("straight_10m", "stsf", 0, env=short))
    assert run_job(job).floor_estimates is not None  # the camera on: a floor by default
    assert run_job({**job, "floor": False}).floor_estimates is None
    asked = {}

    def stop(*args, **kwargs):
        asked.update(kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(demo, "run_episodes", stop)
    with pytest.raises(KeyboardInterrupt):
        demo.run_demo(tmp_path, worlds=1)
    assert asked["floor"] is False


def _row(source: str, successes: list[bool], odometry: list[bool]) -> dict:
    n = len(successes)
    row = {
        "estimator": source,
        "success_rate": {"mean": sum(successes) / n},
        "success_ci95": [0.0, 1.0],
        "collision_rate": {"mean": 0.0},
        "ate_rmse_m": {"mean": 0.1},
        "final_error_m": {"mean": 1.2},
    }
    if source != "odometry":
        row["vs_odometry"] = newcombe_paired(successes, odometry)
    return row


@pytest.mark.parametrize("worlds", [3, 6])
def test_few_worlds_are_marked_and_said(worlds):
    odometry = [False] * worlds
    rows = [_row("odometry", odometry, odometry), _row("stsf", [True] * worlds, odometry)]
    versus = headline(rows)[1]["vs odometry (95 % CI)"]
    words = paragraph(rows, worlds)
    assert versus.endswith(MARK) == (worlds < MIN_PAIRED_WORLDS)
    assert ("too few to separate anything" in words) == (worlds < MIN_PAIRED_WORLDS)
    assert f"arrived on 0 of {worlds}" in words and f"stsf {worlds} of {worlds}" in words


@pytest.mark.slow
def test_the_demos_worlds_separate_odometry_from_stsf(tmp_path):
    """Driven: the follower on odometry and on STSF over the demo's worlds; STSF's success
    minus odometry's, paired world by world, excludes 0 at 95 %."""
    specs = [s for s in demo_specs(DEMO_WORLDS, 0) if s.estimator in ("odometry", "stsf")]
    results = run_episodes(specs, tmp_path, workers=2, desc="")
    success = {
        source: [r.outcome == "goal" for r in results if r.spec["estimator"] == source]
        for source in ("odometry", "stsf")
    }
    paired = newcombe_paired(success["stsf"], success["odometry"])
    assert paired["low"] > 0, paired
    odometry_off = [r.errors[-1] for r in results if r.spec["estimator"] == "odometry"]
    radius = episode_config(DEMO_WORLD, 0, specs[0].env).task.goal_radius
    assert min(odometry_off) > radius  # dead reckoning ends outside the goal radius
