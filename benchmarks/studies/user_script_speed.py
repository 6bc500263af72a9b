"""A user's fifteen-line SB3 script against ``stsf-gym train``: decisions per second on one id.

The same PPO (``configs/agents/ppo.yaml``, ``suites`` section), the same two env processes and
the same budget; the user's side is plain SB3 (``make_vec_env`` on the RL-ready id,
``SubprocVecEnv``), the project's side ``stsf-gym train --algo ppo --suite S --estimator E``
(no demonstrations). They run in turns, ``--rounds`` times, so both see the same load; the
bench's reference workload is taken before and after.

Usage::

    python benchmarks/studies/user_script_speed.py [--suite corridor] [--estimator truth]
        [--decisions 4096] [--rounds 2] [--out benchmarks/results/user-script-speed]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import SubprocVecEnv

import stsf_gym
from stsf_gym.agents.rl.ready import rl_hyperparams
from stsf_gym.agents.training.hyperparams import policy_kwargs_for_sb3
from stsf_gym.io import write_json
from stsf_gym.results.machine_speed import reference_ms


def user_script(suite: str, estimator: str, decisions: int) -> float:
    """Decisions per second of plain SB3 PPO on the RL-ready id (env start-up included)."""
    hp = rl_hyperparams(suite, estimator)
    started = time.perf_counter()
    venv = make_vec_env(stsf_gym.rl_id(suite, estimator), n_envs=2, vec_env_cls=SubprocVecEnv)
    model = PPO(
        "MlpPolicy", venv, policy_kwargs=policy_kwargs_for_sb3(hp.training.policy_kwargs),
        device="cpu", seed=0, **hp.algo_kwargs,
    )  # fmt: skip
    model.learn(decisions)
    venv.close()
    return decisions / (time.perf_counter() - started)


def project_trainer(suite: str, estimator: str, decisions: int) -> float:
    """Decisions per second of ``stsf-gym train --algo ppo`` (its process start-up included)."""
    with tempfile.TemporaryDirectory() as out:
        command = [
            sys.executable, "-m", "stsf_gym.cli", "train", "--algo", "ppo", "--suite", suite,
            "--estimator", estimator, "--timesteps", str(decisions), "--out", out,
            "--set", f"eval_freq={10 * decisions}", "--set", "demonstrations.expert_episodes=0",
        ]  # fmt: skip
        started = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        return decisions / (time.perf_counter() - started)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="corridor")
    parser.add_argument("--estimator", default="truth")
    parser.add_argument("--decisions", type=int, default=4096)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/user-script-speed"))
    args = parser.parse_args()
    before = reference_ms()
    rounds = []
    for _ in range(args.rounds):
        user = user_script(args.suite, args.estimator, args.decisions)
        trainer = project_trainer(args.suite, args.estimator, args.decisions)
        rounds.append({"user_script": user, "stsf_gym_train": trainer, "ratio": user / trainer})
        print(rounds[-1], flush=True)
    result = {
        "suite": args.suite, "estimator": args.estimator, "decisions": args.decisions,
        "env_id": stsf_gym.rl_id(args.suite, args.estimator), "rounds": rounds,
        "ratio_mean": sum(r["ratio"] for r in rounds) / len(rounds),
        "reference_ms_before": before, "reference_ms_after": reference_ms(),
    }  # fmt: skip
    write_json(args.out / "result.json", result)
    print(f"user script / stsf-gym train: {result['ratio_mean']:.2f}")


if __name__ == "__main__":
    main()
