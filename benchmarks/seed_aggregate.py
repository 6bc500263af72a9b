"""Learnt agents against the follower in a benchmark's ``results.json``: the IQM over training
seeds with its interval, and each seed paired with the follower on the same worlds.

Reads the per-episode values the leaderboard keeps, so an aggregate can be recomputed from a
finished benchmark without rerunning an episode. For each training folder and pose source:
the IQM over its runs of each run's success rate and SPL
(:func:`~stsf_gym.experiments.benchmark.intervals.seed_iqm`), the ratio to the follower's
success on the same pose source, and each run's paired difference from the follower
(Newcombe's interval, :func:`~stsf_gym.experiments.benchmark.intervals.newcombe_paired`).

Usage::

    python benchmarks/seed_aggregate.py OUT/SUITE/results.json [--json]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from stsf_gym.experiments.benchmark.trained import aggregate_runs


def aggregate(results: dict) -> list[dict]:
    """The benchmark's own aggregation (:func:`aggregate_runs`) over the per-episode values of
    ``results``' rows: one entry per training folder and pose source."""
    scores = {
        (r["agent"], r["estimator"]): {
            seed: {"success": success, "spl": spl}
            for seed, success, spl in zip(
                r["seeds"], r["success_rate"]["values"], r["spl"]["values"], strict=True
            )
        }
        for r in results["rows"]
    }
    return aggregate_runs(scores)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    entries = aggregate(json.loads(args.results.read_text()))
    if args.json:
        print(json.dumps(entries, indent=1))
        return
    for e in entries:
        low, high = e["success_iqm_ci95"]
        print(
            f"{e['agent']} on {e['estimator']}: success IQM over {e['runs']} seeds "
            f"{e['success_iqm']:.3f} [{low:.3f}, {high:.3f}], per seed "
            f"{', '.join(f'{v:.2f}' for v in e['success_per_run'])}; SPL IQM {e['spl_iqm']:.3f}"
        )
        if "ratio_to_follower" in e:
            ratio = e["ratio_to_follower"]  # None: the follower never succeeded
            print(
                f"  follower {e['follower_success_rate']:.3f}; ratio "
                + ("-" if ratio is None else f"{ratio:.3f}")
            )
            for run, p in zip(range(e["runs"]), e["paired_vs_follower"], strict=True):
                print(
                    f"  seed run {run}: paired difference {p['difference']:+.2f} "
                    f"[{p['low']:+.2f}, {p['high']:+.2f}] over {p['pairs']} worlds"
                )


if __name__ == "__main__":
    main()
