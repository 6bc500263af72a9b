"""How a fresh plain-RL policy's legs end, with SB3's start and with the STOP prior.

A continuous STOP entry declares when above 0; SB3's fresh Gaussian policy puts it above 0 at
half its decisions. This check builds the trainer's first model (``create_model``: plain
``--algo ppo``, no demonstrations) on a suite's training legs, once with
``initial_stop_probability`` 0.5 (SB3's start) and once with the file's prior, lets each drive
``--decisions`` stochastic decisions and counts how the legs end (a declared STOP, a
collision, a success, the time limit) and how many decisions they last.

Usage::

    python benchmarks/stop_prior.py [--suite corridor] [--estimator truth] [--decisions 1500]
        [--out out/stop-prior]

Writes ``stop_prior.json`` (numbers only) to ``--out`` and prints a line per start.
"""

from __future__ import annotations

import argparse
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

from stsf_gym.agents.training.settings import resolve_run
from stsf_gym.agents.training.train import create_model
from stsf_gym.agents.training.training_envs import make_vec_env
from stsf_gym.io import write_json
from stsf_gym.results import stat

SB3_START = 0.5  # a mean of 0: the entry is above 0 at half the decisions


def outcome(info: dict) -> str:
    """How a leg ended, from its last step's info."""
    if info["collision"]:
        return "collision"
    if info["success"]:
        return "success"
    return "stop" if info["stops"] else "time"


def legs(suite: str, estimator: str, decisions: int, prior: float | None) -> dict:
    """The legs a fresh policy drives in ``decisions`` decisions (``prior`` None: the file's)."""
    overrides = {"demonstrations.expert_episodes": 0}
    if prior is not None:
        overrides["initial_stop_probability"] = prior
    run = resolve_run("ppo", estimator, 2048, 0, "irl_corridor", None, overrides, 1, suite)
    with tempfile.TemporaryDirectory() as scratch:
        venv = make_vec_env(1, Path(scratch), "train", **run.env_spec(True))
        try:
            model = create_model(run, Path(scratch), venv)
            obs, ended, lengths, length = venv.reset(), Counter(), [], 0
            for _ in range(decisions):
                action, _ = model.predict(obs, deterministic=False)
                obs, _, done, info = venv.step(action)
                length += 1
                if done[0]:
                    ended[outcome(info[0])] += 1
                    lengths, length = [*lengths, length], 0
        finally:
            venv.close()
    probability = run.hp.training.initial_stop_probability
    return {"initial_stop_probability": probability, "ended": dict(ended)} | {
        "decisions_per_leg": stat(np.array(lengths, float)),
        "median_decisions_per_leg": float(np.median(lengths)) if lengths else None,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--suite", default="corridor")
    parser.add_argument("--estimator", default="truth")
    parser.add_argument("--decisions", type=int, default=1500)
    parser.add_argument("--out", type=Path, default=Path("out/stop-prior"))
    args = parser.parse_args()
    starts = {"sb3": SB3_START, "prior": None}
    results = {
        name: legs(args.suite, args.estimator, args.decisions, p) for name, p in starts.items()
    }
    write_json(args.out / "stop_prior.json", results)
    for name, result in results.items():
        print(
            f"{name} (p={result['initial_stop_probability']}): {sum(result['ended'].values())} "
            f"legs, {result['ended']}, median {result['median_decisions_per_leg']} decisions"
        )


if __name__ == "__main__":
    main()
