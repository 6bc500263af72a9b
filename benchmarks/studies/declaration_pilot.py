"""The pilot of declaration designs: which way of declaring arrival plain RL discovers.

Each design of :mod:`stsf_gym.agents.rl.declaration` is trained as an RL user trains an id:
``make_vec_env`` on ``stsf_gym/RL-<Suite>-Truth-v0`` (with ``declaration=<design>``), SB3 from
scratch (no demonstrations, no prior on the STOP entry), evaluated on 10 full routes of the
suite's val worlds every ``--eval-every`` decisions. Every design gets the same budget, seed,
network and hyper-parameters (``configs/agents/ppo.yaml``, the ``rl-ready`` section), so the
comparison is of the declaration alone. Per design: how the training legs ended and how near
their goals they came (:mod:`stsf_gym.agents.rl.leg_record`: a correct declaration, a
collision, the time limit; whether the robot came within the goal radius, and whether it
declared there), in all and in the first and last tenth of training; false stops within the
first five decisions; the val success and return at each evaluation; decisions per second.

Usage::

    python benchmarks/studies/declaration_pilot.py [--suite corridor]
        [--designs discrete-cheap,stop-cheap] [--algo ppo|sac]
        [--decisions 491520] [--eval-every 40960] [--seed 0]
        [--out benchmarks/results/declaration-pilot] [--check-routes N]

The default 491,520 decisions are a pilot's budget: 40 minutes at the 200 decisions a second
of 2026-12-02's machine (each ``state.json`` holds the bench's reference workload beside its
wall time), a third of the target's two hours a seed. Each design's
unit (``<out>/<algo>-<design>/``) checkpoints at every evaluation (``model.zip``,
``state.json``, SAC's replay buffer) and a rerun resumes it from there; ``result.json`` is
written when it finishes, and a rerun skips it. A rerun with a larger ``--decisions`` and
otherwise the same settings extends a unit; a unit of other settings is set aside.
``--check-routes N`` drives each named unit's finished model on N val routes, its actions
deterministic and sampled, into ``<unit>/routes.json`` (no training).
"""

from __future__ import annotations

import argparse
import csv
import json
import shutil
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.vec_env import SubprocVecEnv

import stsf_gym
from stsf_gym.agents.rl.declaration import declaration
from stsf_gym.agents.rl.leg_record import LEG_KEYS, OUTCOMES, LegRecord
from stsf_gym.agents.rl.ready import rl_hyperparams
from stsf_gym.agents.training.hyperparams import policy_kwargs_for_sb3
from stsf_gym.io import write_atomic, write_json
from stsf_gym.results.machine_speed import reference_ms

EARLY_DECISIONS = 5  # a false stop this early is the fresh policy's, not a learnt one
N_ENVS = 2


def monitor_rows(monitor_dir: Path) -> list[dict]:
    """The training legs of the Monitor files, in the order they ended: each env's legs by the
    decisions it had taken (the clock of a resumed run starts again; decisions do not)."""
    rows = []
    for path in sorted(monitor_dir.glob("*.monitor.csv")):
        with path.open() as handle:
            handle.readline()  # the JSON header
            taken = 0
            for row in csv.DictReader(handle):
                taken += int(row["l"])
                rows.append({**row, "taken": taken})
    return sorted(rows, key=lambda row: row["taken"])


def trim_monitors(monitor_dir: Path, per_env: int) -> None:
    """Keep each Monitor file's legs that ended within its env's first ``per_env`` decisions
    (those of the checkpoint a run resumes from; later ones are driven again)."""
    for path in sorted(monitor_dir.glob("*.monitor.csv")):
        lines = path.read_text().splitlines(keepends=True)
        header, fields, kept, taken = lines[0], lines[1], [], 0
        for line, row in zip(lines[2:], csv.DictReader(lines[1:]), strict=True):
            taken += int(row["l"])
            if taken <= per_env:
                kept.append(line)
        write_atomic(path, "".join([header, fields, *kept]))


def share(rows: list[dict], test) -> float:
    """The share of ``rows`` for which ``test(row)`` holds (0 without rows)."""
    return float(np.mean([bool(test(row)) for row in rows])) if rows else 0.0


def leg_summary(rows: list[dict]) -> dict:
    """How ``rows`` (legs) ended and how near their goals they came (agents/rl/leg_record.py)."""
    if not rows:
        return {"legs": 0}
    reached = [row for row in rows if int(row["in_radius"]) > 0]
    return {
        "legs": len(rows),
        "success": share(rows, lambda row: row["outcome"] == "goal"),
        **{
            f"outcome {name}": share(rows, lambda row, name=name: row["outcome"] == name)
            for name in OUTCOMES
        },
        "within_radius": len(reached) / len(rows),
        "declared_when_within": share(reached, lambda row: row["outcome"] == "goal"),
        "median_closest_m": float(np.median([float(row["closest_m"]) for row in rows])),
        "false_stops_per_leg": float(np.mean([int(row["false_stops"]) for row in rows])),
        **(
            {"weaned": share(rows, lambda row: row["weaned"] == "True")}
            if "weaned" in rows[0]
            else {}
        ),
    }


def leg_outcomes(monitor_dir: Path) -> dict:
    """The training legs in all, in the first and the last tenth of training."""
    rows = monitor_rows(monitor_dir)
    tenth = max(len(rows) // 10, 1)
    lengths = np.array([int(row["l"]) for row in rows])
    return {
        **leg_summary(rows),
        "first_tenth": leg_summary(rows[:tenth]),
        "last_tenth": leg_summary(rows[-tenth:]),
        "short_legs_first_50": float(np.mean(lengths[:50] <= EARLY_DECISIONS)) if rows else 0.0,
        "mean_length": float(lengths.mean()) if rows else 0.0,
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


def extends(old: dict, new: dict) -> bool:
    """Whether a unit of settings ``new`` continues one of ``old``: the same in all but a
    larger budget of decisions."""
    rest = [{k: v for k, v in settings.items() if k != "decisions"} for settings in (old, new)]
    return rest[0] == rest[1] and old.get("decisions", 0) <= new["decisions"]


def finished(unit: Path, settings: dict) -> bool:
    """Whether ``unit`` holds a result of ``settings``. One of a smaller budget, otherwise the
    same, is extended (it resumes from its state); one of other settings (finished or not) is
    set aside, its result kept as ``result.<n>.json``."""
    result, state = unit / "result.json", unit / "state.json"
    for path in (result, state):
        if not path.is_file():
            continue
        held = json.loads(path.read_text())
        if held.get("settings") == settings:
            continue
        if extends(held.get("settings", {}), settings) and state.is_file():
            if path == state:
                write_json(state, {**held, "settings": settings})
                print(f"{unit}: extended to {settings['decisions']:,} decisions")
            else:
                result.unlink()  # written again when the longer run finishes
            continue
        if path == result:
            kept = next(
                unit / f"result.{n}.json"
                for n in range(1, 1000)
                if not (unit / f"result.{n}.json").exists()
            )
            result.rename(kept)
            print(f"{unit}: its result ran with other settings; kept as {kept.name}")
        shutil.rmtree(unit / "monitor", ignore_errors=True)
        for working in ("state.json", "model.zip", "replay.pkl"):
            (unit / working).unlink(missing_ok=True)
    return result.is_file()


def leg_recorded(env_id: str, **kwargs) -> LegRecord:
    """A training env of ``env_id`` whose legs are recorded (agents/rl/leg_record.py)."""
    return LegRecord(gym.make(env_id, **kwargs))


def new_model(algo: str, venv, seed: int, suite: str):
    """A fresh learner: PPO with the RL-ready ids' settings, or SAC with SB3's own."""
    hp = rl_hyperparams(suite, "truth")
    if algo == "ppo":
        kwargs = policy_kwargs_for_sb3(hp.training.policy_kwargs)
        return PPO(
            "MlpPolicy", venv, seed=seed, policy_kwargs=kwargs, device="cpu", **hp.algo_kwargs
        )
    return SAC(
        "MlpPolicy",
        venv,
        seed=seed,
        device="cpu",
        policy_kwargs={"net_arch": [256, 256]},
        learning_starts=2048,
    )


def save_checkpoint(out: Path, model, state: dict) -> None:
    """The model (and SAC's replay buffer), then the state that names them: a kill between
    the two resumes from the previous state's decisions with the newer weights' files, which
    the state's count then overwrites."""
    model.save(out / "model.zip")
    if isinstance(model, SAC):
        model.save_replay_buffer(out / "replay.pkl")
    write_json(out / "state.json", state)


def val_routes(model, eval_env, routes: int = 10, deterministic: bool = True) -> dict:
    """``routes`` full val routes driven deterministically (or sampled): their success,
    return, how they ended and how near their goals they came (the legs' record,
    agents/rl/leg_record.py)."""
    ended: list[dict] = []

    def note(local: dict, _: dict) -> None:
        if local["done"]:
            ended.append(local["info"])

    returns, _ = evaluate_policy(
        model,
        eval_env,
        n_eval_episodes=routes,
        deterministic=deterministic,
        return_episode_rewards=True,
        callback=note,
    )
    return {
        "success": float(np.mean([bool(info.get("is_success")) for info in ended])),
        "return": float(np.mean(returns)),
        "outcomes": {name: sum(info["outcome"] == name for info in ended) for name in OUTCOMES},
        "median_closest_m": float(np.median([info["closest_m"] for info in ended])),
    }


def run_design(
    suite: str, design: str, algo: str, decisions: int, eval_every: int, seed: int, out: Path
) -> dict:
    """Train one design from scratch, or resume it from its last evaluation; its result."""
    env_id = stsf_gym.rl_id(suite, "truth")
    settings = unit_settings(suite, algo, decisions, eval_every, seed)
    state_file = out / "state.json"
    resuming = state_file.is_file()
    if resuming:
        state = json.loads(state_file.read_text())
        trim_monitors(out / "monitor", state["decisions"] // N_ENVS)
        print(f"{out}: resuming at {state['decisions']:,} of {decisions:,} decisions")
    else:
        state = {
            "settings": settings,
            "decisions": 0,
            "val": [],
            "wall_time_s": 0.0,
            "reference_ms_before": reference_ms(),
        }
    kwargs = {"declaration": design}
    weaned = declaration(design).weaned  # its legs record which rule they ran under
    venv = make_vec_env(
        leg_recorded,
        n_envs=N_ENVS,
        seed=seed + state["decisions"],  # a resumed run's legs are new draws
        env_kwargs={"env_id": env_id, **kwargs},
        vec_env_cls=SubprocVecEnv,
        monitor_dir=str(out / "monitor"),
        monitor_kwargs={
            "info_keywords": ("is_success", *LEG_KEYS, *(("weaned",) if weaned else ())),
            "override_existing": not resuming,
        },
    )
    eval_env = make_vec_env(
        leg_recorded,
        n_envs=1,
        seed=seed + 10_000,
        env_kwargs={"env_id": env_id, **kwargs, "split": "val"},
    )
    torch.set_num_threads(1)  # as the trainer: the learner leaves the cores to the env processes
    if resuming:
        model = (PPO if algo == "ppo" else SAC).load(out / "model.zip", env=venv, device="cpu")
        if isinstance(model, SAC):
            model.load_replay_buffer(out / "replay.pkl")
    else:
        model = new_model(algo, venv, seed, suite)
    while state["decisions"] < decisions:
        started = time.perf_counter()
        chunk = min(eval_every, decisions - state["decisions"])
        model.learn(chunk, reset_num_timesteps=False, progress_bar=True)
        val = val_routes(model, eval_env)
        state["decisions"] = int(model.num_timesteps)
        state["wall_time_s"] += time.perf_counter() - started
        state["val"].append({"decisions": state["decisions"], **val})
        save_checkpoint(out, model, state)
        print(json.dumps(state["val"][-1]))
    venv.close()
    eval_env.close()
    return {
        "suite": suite,
        "design": design,
        "algo": algo,
        "seed": seed,
        "decisions": decisions,
        "env_id": env_id,
        "settings": settings,
        "wall_time_s": state["wall_time_s"],
        "decisions_per_second": decisions / state["wall_time_s"],
        "reference_ms_before": state["reference_ms_before"],
        "reference_ms_after": reference_ms(),
        "training_legs": leg_outcomes(out / "monitor"),
        "val": state["val"],
    }


def check_routes(suite: str, algo: str, design: str, unit: Path, routes: int, seed: int) -> dict:
    """A finished unit's model on ``routes`` val routes (the evaluations' first ``routes``),
    its actions chosen deterministically and sampled: whether routes fail where legs succeed
    by the policy's mean or by its draws. Kept in ``<unit>/routes.json``."""
    if not (unit / "result.json").is_file():
        raise SystemExit(f"{unit}: no result.json; run the unit to its end first")
    eval_env = make_vec_env(
        leg_recorded,
        n_envs=1,
        seed=seed + 10_000,
        env_kwargs={"env_id": stsf_gym.rl_id(suite, "truth"), "declaration": design,
                    "split": "val"},
    )  # fmt: skip
    model = (PPO if algo == "ppo" else SAC).load(unit / "model.zip", device="cpu")
    checked = {"routes": routes}
    for way, deterministic in (("deterministic", True), ("sampled", False)):
        model.set_random_seed(seed)
        checked[way] = val_routes(model, eval_env, routes, deterministic)
    eval_env.close()
    write_json(unit / "routes.json", checked)
    return checked


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", default="corridor")
    parser.add_argument("--designs", default="discrete-cheap,stop-cheap")
    parser.add_argument("--algo", choices=("ppo", "sac"), default="ppo")
    parser.add_argument("--decisions", type=int, default=491_520)
    parser.add_argument("--eval-every", type=int, default=40_960)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/declaration-pilot"))
    parser.add_argument(
        "--check-routes",
        type=int,
        metavar="N",
        help="drive each finished unit's model on N val routes, deterministic and sampled",
    )
    args = parser.parse_args()
    for design in args.designs.split(","):
        unit = args.out / f"{args.algo}-{design}"
        if args.check_routes:
            checked = check_routes(
                args.suite, args.algo, design, unit, args.check_routes, args.seed
            )
            print(json.dumps({"design": design, **checked}))
            continue
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
