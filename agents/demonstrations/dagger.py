"""Demonstrations before RL: behaviour cloning, then DAgger rounds (Ross, Gordon and Bagnell
2011, "A reduction of imitation learning and structured prediction to no-regret online
learning").

Round 0: the expert (:class:`~stsf_gym.agents.demonstrations.expert.ExpertLabel`) drives
``expert_episodes`` training episodes; its labels of every control step's state are cloned
into the policy. Rounds
1..``rounds``: the learner drives ``episodes_per_round`` episodes deterministically, the expert
labels every state it reaches, the labels join the data set (aggregation), and the policy is
cloned again on all of it. Plain cloning leaves the learner where the expert never was (after
a late turn, too near a wall, past a goal) with no idea what to do; DAgger's rounds label
exactly those states. After each round the learner is evaluated on the validation worlds and
the round is saved (model and data), so an interrupted stage resumes at its last round.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated

import numpy as np
from stable_baselines3.common.vec_env import VecEnv

from stsf_gym.agents.demonstrations.cloning import CloningConfig, clone, cloning_config
from stsf_gym.agents.training_log import append_row
from stsf_gym.envs.config import build
from stsf_gym.io import write_atomic
from stsf_gym.validation import Range

Episodes = Annotated[int, Range(ge=0)]

DEMONSTRATIONS_CSV = "demonstrations.csv"
COLUMNS = ["round", "control_steps", "decisions", "samples", "wall_time_s", "loss", "val_success"]


@dataclass(frozen=True)
class DemonstrationConfig:
    """The demonstration stage (``demonstrations:`` of the hyper-parameter file); all 0: none."""

    expert_episodes: Episodes = 0
    rounds: Episodes = 0
    episodes_per_round: Episodes = 0
    cloning: dict = field(default_factory=dict)  # CloningConfig's keys

    @property
    def enabled(self) -> bool:
        return self.expert_episodes > 0

    @property
    def clone_settings(self) -> CloningConfig:
        return cloning_config(self.cloning)


def demonstration_config(data: dict | None) -> DemonstrationConfig:
    """A :class:`DemonstrationConfig` from a mapping; unknown keys raise ``ConfigError``."""
    cfg = build(DemonstrationConfig, data or {}, "demonstrations")
    cfg.clone_settings  # noqa: B018 - checks the cloning keys now, before any work
    return cfg


def collect(venv: VecEnv, episodes: int, policy=None) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Drive ``venv`` until ``episodes`` episodes have ended: the expert's actions, or
    ``policy``'s deterministic ones. Return every control step's observation (the policy's
    features) and the expert's label for it (:meth:`ExpertLabel.pop_samples`), the control
    steps taken and the decisions made."""
    obs = venv.reset()
    labels = np.array([info["expert_action"] for info in venv.reset_infos])
    steps = decisions = ended = 0
    while ended < episodes:
        chosen = labels if policy is None else policy.predict(obs, deterministic=True)[0]
        obs, _, dones, infos = venv.step(chosen)
        decisions += len(infos)
        steps += sum(info.get("control_steps", 1) for info in infos)
        ended += int(np.sum(dones))
        labels = np.array(
            [
                (venv.reset_infos[i] if done else info)["expert_action"]
                for i, (done, info) in enumerate(zip(dones, infos, strict=True))
            ]
        )
    samples = [s for s in venv.env_method("pop_samples") if len(s[0])]
    features, actions = (np.concatenate(part) for part in zip(*samples, strict=True))
    return features, actions, steps, decisions


def run_demonstrations(
    model,
    venv: VecEnv,
    cfg: DemonstrationConfig,
    stop_index: int | None,
    out: Path,
    evaluate: Callable[[], float],
    seed: int,
) -> dict:
    """The demonstration stage on ``model``'s policy (resumed from ``out/demonstrations``);
    returns its totals: control steps, decisions, samples, wall time, last val success."""
    folder = out / "demonstrations"
    folder.mkdir(parents=True, exist_ok=True)
    done = _saved_rounds(folder)
    data, totals = _resume(model, folder, done)
    settings = cfg.clone_settings
    for round_ in range(done + 1, cfg.rounds + 1):
        started = time.perf_counter()
        rng = np.random.default_rng([seed, round_])
        episodes = cfg.expert_episodes if round_ == 0 else cfg.episodes_per_round
        obs, actions, steps, decisions = collect(venv, episodes, None if round_ == 0 else model)
        data = (
            (obs, actions)
            if data is None
            else tuple(
                np.concatenate([old, new]) for old, new in zip(data, (obs, actions), strict=True)
            )
        )
        loss = clone(model.policy, *data, stop_index, settings, rng)
        success = evaluate()
        totals = {
            "round": round_,
            "control_steps": totals["control_steps"] + steps,
            "decisions": totals["decisions"] + decisions,
            "samples": len(data[0]),
            "wall_time_s": totals["wall_time_s"] + time.perf_counter() - started,
            "loss": loss,
            "val_success": success,
        }
        _save_round(model, folder, round_, data, totals)
        append_row(out / DEMONSTRATIONS_CSV, COLUMNS, [totals[c] for c in COLUMNS])
    return totals


def _saved_rounds(folder: Path) -> int:
    """The last round saved in ``folder`` (-1: none)."""
    rounds = [int(p.stem.split("_")[1]) for p in folder.glob("round_*.zip")]
    return max(rounds, default=-1)


def _resume(model, folder: Path, done: int) -> tuple[tuple | None, dict]:
    if done < 0:
        empty = {"control_steps": 0, "decisions": 0, "wall_time_s": 0.0}
        return None, empty
    model.policy.load_state_dict(type(model).load(folder / f"round_{done}.zip").policy.state_dict())
    saved = np.load(folder / "data.npz")
    totals = {k: float(saved[k]) for k in ("control_steps", "decisions", "wall_time_s")}
    return (saved["observations"], saved["actions"]), totals


def _save_round(model, folder: Path, round_: int, data: tuple, totals: dict) -> None:
    """The data set, then the round's model: a round's zip implies its data (both atomic)."""
    import io

    buffer = io.BytesIO()
    np.savez(
        buffer,
        observations=data[0],
        actions=data[1],
        **{k: totals[k] for k in ("control_steps", "decisions", "wall_time_s")},
    )
    write_atomic(folder / "data.npz", buffer.getvalue())
    buffer = io.BytesIO()
    model.save(buffer)
    write_atomic(folder / f"round_{round_}.zip", buffer.getvalue())
