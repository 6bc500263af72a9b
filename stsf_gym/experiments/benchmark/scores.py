"""What one benchmark episode scores, and a row of the leaderboard over episodes.

- **success**: every goal of the route reached by a declared stop within ``task.goal_radius``
  (``outcome == "goal"``);
- **SPL**, success weighted by path length (Anderson et al. 2018, "On evaluation of embodied
  navigation agents"): ``S * l / max(p, l)`` with ``l`` the route's geodesic length
  (``navigation["geodesic_length_m"]``: the shortest collision-free path from the episode's
  true start through every goal in order, walls and obstacles grown by the robot's body radius,
  :mod:`stsf_gym.envs.worlds.geodesic`, at most a few millimetres short per turn) and ``p`` the
  distance the robot drove (true). The centre line (``route_length_m``) would not do: a
  follower cutting corners drives less than it, and its SPL would be 1 whatever it did. A
  robot that drives the geodesic scores 1; one that declares its stop up to ``goal_radius``
  short of a goal may drive a little less than ``l``, and scores 1 too;
- the **true distance to the goal at each declared stop** (the agent's belief against the
  truth at the moment it matters); collisions, missed stops, time-outs.
"""

from __future__ import annotations

from collections import Counter

from stsf_gym.experiments.benchmark.intervals import stratified_bootstrap, wilson
from stsf_gym.results import stat

OUTCOMES = ("goal", "missed", "collision", "time")
NEAR_MISS_M = 1.0  # a missed stop closer than this to its goal was in the right place, roughly


def spl(success: bool, shortest: float, travelled: float) -> float:
    """Success weighted by (normalised inverse) path length of one episode."""
    if not success:
        return 0.0
    return float(shortest / max(travelled, shortest)) if shortest > 0 else 1.0


def episode_scores(result: dict) -> dict:
    """The scores of one evaluate cell's result."""
    navigation, success = result["navigation"], result["outcome"] == "goal"
    stops = navigation["stops"]
    return {
        "success": success,
        "spl": spl(success, navigation["geodesic_length_m"], result["distance"]),
        "outcome": result["outcome"],
        "stop_distances_m": [stop["true_distance_m"] for stop in stops],
        "goals_reached": sum(stop["success"] for stop in stops),
        "goals": navigation["goals"],
        "ate_rmse_m": result["metrics"]["ate_rmse_m"],
    }


def leaderboard_row(agent: str, estimator: str, scores: list[dict], seeds: list[int]) -> dict:
    """One row: rates with their Wilson intervals, SPL with a bootstrap interval stratified by
    the route's number of goals, distances at the stops, ATE; per-episode values kept."""
    successes = [s["success"] for s in scores]
    outcomes = Counter(s["outcome"] for s in scores)
    strata: dict[int, list[float]] = {}
    for s in scores:
        strata.setdefault(s["goals"], []).append(s["spl"])
    spl_interval = stratified_bootstrap(list(strata.values()))
    return {
        "agent": agent,
        "estimator": estimator,
        "episodes": len(scores),
        "seeds": seeds,
        "success_rate": stat(successes),
        "success_ci95": list(wilson(sum(successes), len(successes))),
        "spl": stat(s["spl"] for s in scores),
        "spl_ci95": [spl_interval["low"], spl_interval["high"]],
        **{f"{o}_rate": outcomes[o] / len(scores) for o in OUTCOMES if o != "goal"},
        "collision_ci95": list(wilson(outcomes["collision"], len(scores))),
        "stop_distance_m": stat(d for s in scores for d in s["stop_distances_m"]),
        "first_stop_distance_m": stat(
            s["stop_distances_m"][0] if s["stop_distances_m"] else None for s in scores
        ),
        "goals_reached_share": stat(s["goals_reached"] / s["goals"] for s in scores),
        "ate_rmse_m": stat(s["ate_rmse_m"] for s in scores),
        "failures": failure_breakdown(scores),
    }


def failure_breakdown(scores: list[dict]) -> dict[str, int]:
    """Where the failed episodes went wrong: a declared stop near the goal (within
    :data:`NEAR_MISS_M`: the estimate was off by a little), far from it (lost: a wrong turn or
    an estimate metres off), a collision, or the time limit."""
    counts = dict.fromkeys(("missed_near", "missed_far", "collision", "time"), 0)
    for s in scores:
        if s["outcome"] == "missed":
            near = s["stop_distances_m"][-1] < NEAR_MISS_M
            counts["missed_near" if near else "missed_far"] += 1
        elif s["outcome"] in counts:
            counts[s["outcome"]] += 1
    return counts
