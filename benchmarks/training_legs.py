"""What a reward stage's training legs did, early and late: how many ended in a correct
declaration, how many ran to the time limit, how long they lasted and what they returned.

A run's ``episodes.csv`` logs every training leg of its reward stage (decisions, return,
success); a leg that neither succeeded nor ended early ran to the training env's time limit
(``train_env.sim.max_episode_seconds`` at one decision every ``decision_steps`` control steps
of ``sim.control_dt``). For plain RL this says what the policy learnt where val success stays
at 0: to declare, or only to keep a leg going.

Usage::

    python benchmarks/training_legs.py RUN [RUN ...] [--window 200] [--out FILE.json]

Prints a Markdown table (one row per run, its first and last ``window`` legs); ``--out`` writes
the numbers (each ``{mean, std, count, values}`` where a measure has several values).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

import numpy as np

from stsf_gym.config import load_config
from stsf_gym.io import markdown_table, write_json
from stsf_gym.results import stat
from stsf_gym.results.provenance import provenance


def time_limit_decisions(train: dict) -> int:
    """The decisions of a leg that runs to the training env's time limit (``train.json``)."""
    hyperparams = train["hyperparams"]
    limit_s = hyperparams["train_env"]["sim"]["max_episode_seconds"]
    control_dt = load_config().sim.control_dt
    return math.ceil(round(limit_s / control_dt / train["decision_steps"], 9))


def window_measures(legs: list[dict], limit: int) -> dict:
    """Counts and statistics of ``legs`` (rows of ``episodes.csv``)."""
    lengths = [int(leg["length"]) for leg in legs]
    successes = [bool(int(leg["success"])) for leg in legs]
    return {
        "legs": len(legs),
        "correct_declarations": sum(successes),
        "time_limit": sum(n >= limit and not s for n, s in zip(lengths, successes, strict=True)),
        "median_decisions": float(np.median(lengths)),
        "return": stat(float(leg["reward"]) for leg in legs),
    }


def run_measures(run: Path, window: int) -> dict:
    """The run's legs in all, and its first and last ``window``."""
    train = json.loads((run / "train.json").read_text())
    with (run / "episodes.csv").open() as file:
        legs = list(csv.DictReader(file))
    limit = time_limit_decisions(train)
    return {
        "algo": train["algo"],
        "seed": train["seed"],
        "time_limit_decisions": limit,
        "all": window_measures(legs, limit),
        "first": window_measures(legs[:window], limit),
        "last": window_measures(legs[-window:], limit),
    }


def markdown(runs: dict[str, dict], window: int) -> str:
    """One row per run: its legs, correct declarations, and early against late."""

    def side(m: dict) -> str:
        return f"{m['time_limit']} / {m['median_decisions']:g} / {m['return']['mean']:+.1f}"

    return markdown_table(
        [
            {
                "run": name,
                "legs": m["all"]["legs"],
                "correct declarations": m["all"]["correct_declarations"],
                f"first {window}: at the time limit / median decisions / mean return": side(
                    m["first"]
                ),
                f"last {window}: the same": side(m["last"]),
            }
            for name, m in runs.items()
        ]
    )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="run folders (with episodes.csv)")
    parser.add_argument("--window", type=int, default=200, help="legs at each end (200)")
    parser.add_argument("--out", type=Path, help="write the numbers here (JSON)")
    args = parser.parse_args(argv)
    for run in args.runs:
        for needed in ("train.json", "episodes.csv"):
            if not (run / needed).is_file():
                parser.error(f"{run}: no {needed} (not a finished training run)")
    if args.window < 1:
        parser.error(f"--window must be at least 1, got {args.window}")
    runs = {str(run): run_measures(run, args.window) for run in args.runs}
    print(markdown(runs, args.window))
    if args.out:
        write_json(args.out, {"window": args.window, "runs": runs, "provenance": provenance()})


if __name__ == "__main__":
    main()
