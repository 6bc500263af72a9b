"""Does the decision interval change what the estimators do? The follower at one decision per
control step against one per ``k`` steps, paired on the same worlds and seeds.

A learnt policy decides every ``decision_steps`` control steps (agents/decision_interval.py)
while the estimator updates on every step. This check drives the scripted follower both ways
on a suite's test worlds with the STOP action, for each estimator, and reports the success
rates and the ATE (mean, std over worlds, and the paired difference with its 95 % interval).
The interval is harmless to the estimators when the paired ATE difference is inside the
spread of the ATE over worlds.

Usage::

    python benchmarks/decision_interval.py [--suite corridor] [--worlds 10] [--k 5]
        [--estimators truth,odometry,stsf,ekf] [--workers 2] [--out out/decision-interval]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.config_files import deep_merge
from stsf_gym.envs.suite import load_suite
from stsf_gym.experiments.benchmark.intervals import paired_bootstrap
from stsf_gym.experiments.episodes import EpisodeSpec, run_episodes
from stsf_gym.io import write_json
from stsf_gym.metrics import ate_rmse
from stsf_gym.results import stat
from stsf_gym.results.provenance import provenance


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--suite", default="corridor")
    parser.add_argument("--worlds", type=int, default=10)
    parser.add_argument("--k", type=int, default=5, help="control steps per decision")
    parser.add_argument("--estimators", default="truth,odometry,stsf,ekf")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("out/decision-interval"))
    args = parser.parse_args()
    env = deep_merge(load_suite(args.suite).episode_env, {"task": {"stop_action": True}})
    rows = []
    for estimator in args.estimators.split(","):
        by_k = {}
        for k in (1, args.k):
            specs = [
                EpisodeSpec(
                    "generated:test",
                    estimator,
                    args.seed + w,
                    env=env,
                    agent_options={"decision_steps": k},
                )
                for w in range(args.worlds)
            ]
            by_k[k] = run_episodes(specs, args.out / "episodes", args.workers, f"{estimator} k={k}")
        ate = {k: [ate_rmse(e.true_xy, e.estimate_xy) for e in eps] for k, eps in by_k.items()}
        rows.append(
            {
                "estimator": estimator,
                "worlds": args.worlds,
                **{
                    f"success_k{k}": stat(float(e.outcome == "goal") for e in by_k[k]) for k in by_k
                },
                **{f"ate_m_k{k}": stat(ate[k]) for k in ate},
                "ate_difference_m": paired_bootstrap(ate[args.k], ate[1]),
            }
        )
        print(_line(rows[-1], args.k), flush=True)
    record = provenance(env, seeds=range(args.seed, args.seed + args.worlds))
    write_json(
        args.out / "results.json",
        {"suite": args.suite, "k": args.k, "rows": rows, "provenance": record},
    )
    (args.out / "results.md").write_text("\n".join(_line(r, args.k) for r in rows) + "\n")


def _line(row: dict, k: int) -> str:
    diff = row["ate_difference_m"]
    return (
        f"{row['estimator']:>10}: success {row['success_k1']['mean']:.2f} (k=1) "
        f"{row[f'success_k{k}']['mean']:.2f} (k={k}) of {row['worlds']}; ATE "
        f"{row['ate_m_k1']['mean']:.3f} +- {row['ate_m_k1']['std']:.3f} m (k=1), "
        f"{row[f'ate_m_k{k}']['mean']:.3f} +- {row[f'ate_m_k{k}']['std']:.3f} m (k={k}); "
        f"paired difference {diff['difference']:+.3f} m, 95 % CI [{diff['low']:+.3f}, "
        f"{diff['high']:+.3f}]"
    )


if __name__ == "__main__":
    main()
