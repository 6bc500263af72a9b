"""The benchmark's scores and intervals: SPL on hand-made episodes, Wilson, the paired
difference (Newcombe 1998) on synthetic outcomes, the stratified bootstrap."""

from __future__ import annotations

import numpy as np
import pytest

from stsf_gym.experiments.benchmark.intervals import (
    iqm,
    newcombe_paired,
    paired_bootstrap,
    paired_seed_iqm,
    seed_iqm,
    stratified_bootstrap,
    wilson,
)
from stsf_gym.experiments.benchmark.report import agent_name
from stsf_gym.experiments.benchmark.scores import episode_scores, leaderboard_row, spl


def result(outcome: str, distance: float, shortest: float, stops=(), goals: int = 1) -> dict:
    """An evaluate cell's result, made by hand (``shortest``: the route's geodesic length)."""
    return {
        "outcome": outcome,
        "distance": distance,
        "metrics": {"ate_rmse_m": 0.1},
        "navigation": {"goals": goals, "geodesic_length_m": shortest, "stops": list(stops)},
    }


def test_spl_on_hand_made_episodes():
    assert spl(True, 10.0, 12.5) == pytest.approx(0.8)
    assert spl(True, 10.0, 9.0) == 1.0  # a shorter drive than the route counts as the route
    assert spl(False, 10.0, 10.0) == 0.0
    stop = {"true_distance_m": 0.1, "success": True}
    episodes = [
        result("goal", 12.5, 10.0, [stop]),  # 0.8
        result("goal", 20.0, 10.0, [stop]),  # 0.5
        result("missed", 10.0, 10.0, [{"true_distance_m": 0.6, "success": False}]),  # 0
        result("collision", 3.0, 10.0),  # 0
    ]
    scores = [episode_scores(e) for e in episodes]
    row = leaderboard_row("follower", "odometry", scores, [0, 1, 2, 3])
    assert row["spl"]["mean"] == pytest.approx((0.8 + 0.5) / 4)
    assert row["success_rate"]["mean"] == 0.5
    assert row["stop_distance_m"]["values"] == [0.1, 0.1, 0.6]
    assert row["failures"] == {"missed_near": 1, "missed_far": 0, "collision": 1, "time": 0}
    low, high = row["success_ci95"]
    assert low < 0.5 < high


def test_wilson_interval_known_values():
    # Wilson (1927) / Newcombe (1998, Stat. Med. 17:857) table I: 81/263 -> 0.2553-0.3662
    low, high = wilson(81, 263)
    assert (low, high) == pytest.approx((0.2553, 0.3662), abs=1e-4)
    assert wilson(0, 10)[0] == 0.0 and wilson(0, 10)[1] == pytest.approx(0.2775, abs=1e-4)
    for trials in range(1, 200):  # every interval holds its rate (a plot's error bars >= 0)
        for successes in (0, trials // 3, trials):
            low, high = wilson(successes, trials)
            assert low <= successes / trials <= high


def test_paired_difference_on_synthetic_outcomes():
    rng = np.random.default_rng(0)
    same = rng.random(100) < 0.6
    identical = newcombe_paired(same, same)
    assert identical["difference"] == 0.0 and identical["low"] < 0 < identical["high"]
    better = same | (rng.random(100) < 0.5)  # succeeds wherever the other does, and more
    result = newcombe_paired(better, same)
    assert result["only_second"] == 0 and result["only_first"] > 10
    assert result["low"] > 0  # the interval excludes 0
    assert newcombe_paired(same, better)["high"] < 0


def test_paired_interval_covers_the_true_difference():
    """Over many synthetic paired data sets (shared luck plus a 10 % better first source) the
    95 % interval holds the true difference in about 95 % of them, the pairing keeps it
    narrower than independent Wilson intervals would."""
    rng = np.random.default_rng(1)
    covered, widths = [], []
    for _ in range(300):
        luck = rng.random(100)
        first, second = luck < 0.7, luck < 0.6  # true difference 0.1
        flip = rng.random(100) < 0.1  # some unshared luck
        second = np.where(flip, rng.random(100) < 0.6, second)
        truth = 0.7 - 0.6
        interval = newcombe_paired(first, second)
        covered.append(interval["low"] <= truth <= interval["high"])
        widths.append(interval["high"] - interval["low"])
    assert 0.92 <= np.mean(covered) <= 0.995
    independent = 2 * 1.96 * np.sqrt(2 * 0.65 * 0.35 / 100)
    assert np.mean(widths) < independent


def test_bootstraps_and_iqm():
    interval = paired_bootstrap([1.0, 2.0, 3.0, 4.0], [0.0, 1.0, 2.0, 3.0])
    assert interval == {"difference": 1.0, "low": 1.0, "high": 1.0}  # constant differences
    strata = [[0.0] * 50, [1.0] * 50]
    whole = stratified_bootstrap(strata)
    assert whole["estimate"] == 0.5 and whole["low"] == whole["high"] == 0.5  # no spread
    spread = stratified_bootstrap([[0.0, 1.0] * 25, [0.5] * 10])
    assert spread["low"] < spread["estimate"] < spread["high"]
    assert iqm([0, 1, 2, 3, 4, 5, 6, 100]) == pytest.approx(np.mean([2, 3, 4, 5]))


def test_a_paired_iqm_difference_removes_the_luck_both_sides_share():
    rng = np.random.default_rng(3)
    # 3 runs x 60 worlds; the second succeeds where the first does, and on 6 worlds more
    first = rng.random((3, 60)) < 0.5
    second = first.copy()
    second[:, :6], first[:, :6] = True, False
    paired = paired_seed_iqm(first, second)
    expected = seed_iqm(first)["estimate"] - seed_iqm(second)["estimate"]
    assert paired["difference"] == pytest.approx(expected) == pytest.approx(-0.1)
    assert paired["low"] < -0.1 < paired["high"] < 0  # only the 6 worlds' draws vary
    alone = seed_iqm(second)
    assert paired["high"] - paired["low"] < alone["high"] - alone["low"]
    scores = rng.random((3, 60))  # a constant shift: no spread at all
    assert paired_seed_iqm(scores + 0.1, scores)["low"] == pytest.approx(0.1)
    assert paired_seed_iqm(scores + 0.1, scores)["high"] == pytest.approx(0.1)
    with pytest.raises(ValueError, match="one non-empty shape"):
        paired_seed_iqm(first, second[:2])


def test_an_agent_has_one_name_in_every_table(tmp_path):
    """A one-seed run's model and its training folder (the IQM table's row) read the same;
    it was ``train/ppo-stsf`` in the leaderboard and ``ppo-stsf`` in the IQM table."""
    run = tmp_path / "train" / "ppo-stsf"
    assert agent_name(str(run / "model.zip")) == agent_name(str(run)) == "ppo-stsf"
    assert agent_name(str(run / "seed-2" / "model.zip")) == "ppo-stsf/seed-2"
    assert agent_name(str(tmp_path / "my_agent.zip")) == "my_agent"
    assert agent_name("follower") == "follower"
