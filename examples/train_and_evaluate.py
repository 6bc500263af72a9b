"""Train a PPO agent on a pose source, then evaluate it beside the path follower.

The Python side of ``stsf-gym train`` and ``stsf-gym evaluate --agent``: :func:`train` writes
``model.zip`` (with what it was trained on inside), ``learning_curve.png`` and ``train.json``;
:func:`evaluate` runs any agent, the follower or a saved model, through the same episodes and
writes ``results.json``. A real run trains for tens of thousands of steps with the
hyper-parameters of ``configs/agents/ppo.yaml`` (``stsf-gym train --algo ppo --estimator truth
--timesteps 60000``); :data:`SHORT` shrinks it to one PPO update of 64 steps on 3 s episodes,
so that this script shows the whole round trip in seconds (the agent learns nothing in that
time).

    python examples/train_and_evaluate.py [--out out/train_and_evaluate]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.agents.training.train import train
from stsf_gym.experiments.evaluate import evaluate

#: Hyper-parameter overrides (any key of configs/agents/ppo.yaml) for a run of seconds.
SHORT = {
    "n_steps": 64,
    "batch_size": 32,
    "eval_freq": 64,
    "n_eval_episodes": 1,
    "env.sim.max_episode_seconds": 3.0,
}
#: The evaluation's env: the true pose needs no camera; episodes cut at 10 s.
EVALUATION_ENV = {"camera": {"enabled": False}, "sim": {"max_episode_seconds": 10.0}}


def main(argv: list[str] | None = None) -> dict[str, dict]:
    """Train on ``truth``, evaluate the model and the follower; return their results rows."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/train_and_evaluate"))
    args = parser.parse_args(argv)
    run = args.out / "ppo-truth"
    summary = train("ppo", "truth", run, timesteps=64, n_envs=1, overrides=SHORT)
    print(f"trained {summary['timesteps']} steps: {run / 'model.zip'}")
    rows = {}
    for agent in ("follower", str(run / "model.zip")):
        name = Path(agent).stem
        result, _ = evaluate(
            args.out / f"evaluate-{name}", ["truth"], 1, agent=agent, workers=1, env=EVALUATION_ENV
        )
        rows[name] = row = result["rows"][0]
        print(f"{name}: {outcome(row)}, ATE {row['ate_rmse_m']['mean']:.3f} m")
    return rows


def outcome(row: dict) -> str:
    """How the row's one episode ended, in words."""
    if row["success_rate"]["mean"] == 1:
        return "reached the goal"
    distance = row["distance_before_failure_m"]["mean"]
    if row["time_limit_rate"]["mean"] == 1:
        limit = EVALUATION_ENV["sim"]["max_episode_seconds"]
        return f"cut at the {limit:g} s time limit after {distance:.2f} m"
    if row["collision_rate"]["mean"] == 1:
        return f"collided after {distance:.2f} m"
    return f"stopped off the goal after {distance:.2f} m"


if __name__ == "__main__":
    main()
