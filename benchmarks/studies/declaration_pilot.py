"""The pilot of declaration designs: which way of declaring arrival plain RL discovers.

Each design of :mod:`stsf_gym.agents.rl.declaration` is trained as an RL user trains an id:
``make_vec_env`` on ``stsf_gym/RL-<Suite>-Truth-v0`` (with ``declaration=<design>``), SB3 from
scratch (no demonstrations, no prior on the STOP entry), ``EvalCallback`` on 10 full routes of
the suite's val worlds every ``--eval-every`` decisions. Every design gets the same budget,
seed, network and hyper-parameters (``configs/agents/ppo.yaml``, the ``suites`` section), so
the comparison is of the declaration alone. Per design: how the training legs ended (a false
stop within the first five decisions, a correct declaration, a collision, the time limit),
correct declarations early and late in training, the val success at each evaluation, and the
decisions per second.

Usage::

    python benchmarks/studies/declaration_pilot.py [--suite corridor]
        [--designs stop-goes-on,stop-graded,discrete] [--algo ppo|sac]
        [--decisions 204800] [--seed 0]
        [--out benchmarks/results/declaration-pilot]

Each design's unit (``<out>/<algo>-<design>/result.json``) is written when it finishes; a rerun
skips finished units, so the pilot resumes unit by unit.
"""

from __future__ import annotations

import argparse
import csv
import json
import shutil
import time
from pathlib import Path

import numpy as np
import torch
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.callbacks import EvalCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import SubprocVecEnv

import stsf_gym
from stsf_gym.agents.rl.ready import rl_hyperparams
from stsf_gym.agents.training.hyperparams import policy_kwargs_for_sb3
from stsf_gym.io import write_json
from stsf_gym.results.machine_speed import reference_ms

EARLY_DECISIONS = 5  # a false stop this early is the fresh policy's, not a learnt one


def leg_outcomes(monitor_dir: Path) -> dict:
    """How the training legs ended, from the Monitor files (is_success, length, reward)."""
    rows = []
    for path in sorted(monitor_dir.glob("*.monitor.csv")):
        with path.open() as handle:
            handle.readline()  # the JSON header
            rows += list(csv.DictReader(handle))
    rows.sort(key=lambda row: float(row["t"]))
    success = np.array([row["is_success"] == "True" for row in rows])
    lengths = np.array([int(row["l"]) for row in rows])
    tenth = max(len(rows) // 10, 1)
    return {
        "legs": len(rows),
        "successes": int(success.sum()),
        "success_first_tenth": float(success[:tenth].mean()) if len(rows) else 0.0,
        "success_last_tenth": float(success[-tenth:].mean()) if len(rows) else 0.0,
        "short_legs_first_50": float(np.mean(lengths[:50] <= EARLY_DECISIONS))
        if len(rows)
        else 0.0,
        "mean_length": float(lengths.mean()) if len(rows) else 0.0,
    }


def unit_settings(suite: str, algo: str, decisions: int, eval_every: int, seed: int) -> dict:
    """What a unit's result depends on besides its design: a unit run with other settings is
    run again (its result kept beside, as ``result.<n>.json``)."""
    hp = rl_hyperparams(suite, "truth")
    learner = {"policy_kwargs": hp.training.policy_kwargs, **hp.algo_kwargs}
    return {
        "suite": suite,
        "decisions": decisions,
        "eval_every": eval_every,
        "seed": seed,
        "learner": learner if algo == "ppo" else {"sac": "SB3 defaults, net_arch [256, 256]"},
    }


def finished(unit: Path, settings: dict) -> bool:
    """Whether ``unit`` holds a result of ``settings``; one of other settings is set aside."""
    result = unit / "result.json"
    if not result.is_file():
        return False
    if json.loads(result.read_text()).get("settings") == settings:
        return True
    kept = next(
        unit / f"result.{n}.json"
        for n in range(1, 1000)
        if not (unit / f"result.{n}.json").exists()
    )
    result.rename(kept)
    for working in ("monitor", "eval"):
        shutil.rmtree(unit / working, ignore_errors=True)
    print(f"{unit}: its result ran with other settings; kept as {kept.name}, running again")
    return False


def run_design(
    suite: str, design: str, algo: str, decisions: int, eval_every: int, seed: int, out: Path
) -> dict:
    """Train one design from scratch and return its measured unit."""
    env_id = stsf_gym.rl_id(suite, "truth")
    hp = rl_hyperparams(suite, "truth")
    kwargs = {"declaration": design}
    venv = make_vec_env(
        env_id,
        n_envs=2,
        seed=seed,
        env_kwargs=kwargs,
        vec_env_cls=SubprocVecEnv,
        monitor_dir=str(out / "monitor"),
        monitor_kwargs={"info_keywords": ("is_success",)},
    )
    eval_env = make_vec_env(
        env_id, n_envs=1, seed=seed + 10_000, env_kwargs={**kwargs, "split": "val"}
    )
    policy_kwargs = policy_kwargs_for_sb3(hp.training.policy_kwargs)
    if algo == "ppo":
        model = PPO(
            "MlpPolicy",
            venv,
            seed=seed,
            policy_kwargs=policy_kwargs,
            device="cpu",
            **hp.algo_kwargs,
        )
    else:
        model = SAC(
            "MlpPolicy",
            venv,
            seed=seed,
            device="cpu",
            policy_kwargs={"net_arch": [256, 256]},
            learning_starts=2048,
        )
    callback = EvalCallback(
        eval_env,
        n_eval_episodes=10,
        eval_freq=eval_every // 2,
        log_path=str(out / "eval"),
        deterministic=True,
        verbose=0,
    )
    torch.set_num_threads(1)  # as the trainer: the learner leaves the cores to the env processes
    started, before = time.perf_counter(), reference_ms()
    model.learn(decisions, callback=callback, progress_bar=True)
    seconds = time.perf_counter() - started
    venv.close()
    eval_env.close()
    evaluations = np.load(out / "eval" / "evaluations.npz")
    return {
        "suite": suite,
        "design": design,
        "algo": algo,
        "seed": seed,
        "decisions": decisions,
        "env_id": env_id,
        "settings": unit_settings(suite, algo, decisions, eval_every, seed),
        "wall_time_s": seconds,
        "decisions_per_second": decisions / seconds,
        "reference_ms_before": before,
        "reference_ms_after": reference_ms(),
        "training_legs": leg_outcomes(out / "monitor"),
        "val": [
            {"decisions": int(t), "success": float(np.mean(s)), "return": float(np.mean(r))}
            for t, s, r in zip(
                evaluations["timesteps"],
                evaluations["successes"],
                evaluations["results"],
                strict=True,
            )
        ],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="corridor")
    parser.add_argument("--designs", default="stop-goes-on,stop-graded,discrete")
    parser.add_argument("--algo", choices=("ppo", "sac"), default="ppo")
    parser.add_argument("--decisions", type=int, default=204_800)
    parser.add_argument("--eval-every", type=int, default=40_960)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/declaration-pilot"))
    args = parser.parse_args()
    for design in args.designs.split(","):
        unit = args.out / f"{args.algo}-{design}"
        settings = unit_settings(args.suite, args.algo, args.decisions, args.eval_every, args.seed)
        if finished(unit, settings):
            print(f"{unit}: finished, skipped")
            continue
        result = run_design(
            args.suite, design, args.algo, args.decisions, args.eval_every, args.seed, unit
        )
        write_json(unit / "result.json", result)
        print(json.dumps({k: result[k] for k in ("design", "algo", "val", "training_legs")}))


if __name__ == "__main__":
    main()
