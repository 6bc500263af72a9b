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
exactly those states. Each round's episodes start from the round's own seed
(:func:`round_seed`). After each round the learner is evaluated on the validation worlds (the
same ones each round) and the round is saved (model, data, log), so an interrupted stage
resumes after its last round with the result an uninterrupted one gives. The stage ends with
the round's policy that did best on the validation worlds, the latest of equals (``keep:
best``, the default), or with the last round's (``keep: last``): later rounds add data where
the learner strays, yet a round can lose what an earlier one had (docs/agents-results.md
measures both).
"""

from __future__ import annotations

import io
import json
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from stable_baselines3.common.vec_env import VecEnv

from stsf_gym.agents.demonstrations.cloning import CloningConfig, clone, cloning_config
from stsf_gym.envs.config import build
from stsf_gym.io import write_atomic, write_json
from stsf_gym.validation import Range

Episodes = Annotated[int, Range(ge=0)]

DEMONSTRATIONS_JSON = "demonstrations.json"


@dataclass(frozen=True)
class DemonstrationConfig:
    """The demonstration stage (``demonstrations:`` of the hyper-parameter file); all 0: none."""

    expert_episodes: Episodes = 0
    rounds: Episodes = 0
    episodes_per_round: Episodes = 0
    every_control_step: bool = True  # label the held steps between decisions too (else: not)
    keep: Literal["last", "best"] = "best"  # the policy the stage ends with (see the module)
    #: the pose the teaching follower drives on: ``truth`` (privileged, "learning by cheating")
    #: or ``estimate``, the student's own (its labels then follow from what the student sees)
    teacher_pose: Literal["truth", "estimate"] = "truth"
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


def collect(
    venv: VecEnv,
    episodes: int,
    policy=None,
    every_step: bool = True,
    on_episodes: Callable[[int], object] = lambda ended: None,
) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Drive ``venv`` until ``episodes`` episodes have ended: the expert's actions, or
    ``policy``'s deterministic ones. Return the observations (the policy's features) and the
    expert's labels of every control step (:meth:`ExpertLabel.pop_samples`), or of every
    decision only, the control steps taken and the decisions made. ``on_episodes(n)`` hears
    of every step that ended ``n`` episodes (a progress bar)."""
    obs = venv.reset()
    labels = np.array([info["expert_action"] for info in venv.reset_infos])
    observations, actions = [], []
    steps = decisions = ended = 0
    while ended < episodes:
        observations.append(obs)
        actions.append(labels)
        chosen = labels if policy is None else policy.predict(obs, deterministic=True)[0]
        obs, _, dones, infos = venv.step(chosen)
        decisions += len(infos)
        steps += sum(info.get("control_steps", 1) for info in infos)
        finished = int(np.sum(dones))
        if finished:
            on_episodes(min(finished, episodes - ended))  # those past the count are not kept
        ended += finished
        labels = np.array(
            [
                (venv.reset_infos[i] if done else info)["expert_action"]
                for i, (done, info) in enumerate(zip(dones, infos, strict=True))
            ]
        )
    samples = [s for s in venv.env_method("pop_samples") if len(s[0])]
    if not every_step:
        return np.concatenate(observations), np.concatenate(actions), steps, decisions
    features, labelled = (np.concatenate(part) for part in zip(*samples, strict=True))
    return features, labelled, steps, decisions


def run_demonstrations(
    model,
    venv: VecEnv,
    cfg: DemonstrationConfig,
    stop_index: int | None,
    out: Path,
    evaluate: Callable[[], tuple[list[bool], list[float]]],
    seed: int,
    made_by: str,
    progress: Callable[[int], object] = lambda episodes: None,
    on_round: Callable[[list[dict]], object] = lambda history: None,
) -> dict:
    """The demonstration stage on ``model``'s policy (resumed from ``out/demonstrations`` when
    the same code and settings, ``made_by``, logged it); each round is logged in
    ``out/demonstrations.json`` (its totals, the success and return of each validation
    episode) and then passed, with those before it, to ``on_round``; ``progress(n)`` hears of
    ``n`` more episodes driven (:func:`stage_episodes` in all). Returns the last round's
    totals, ``kept_round``, the round whose policy ``model`` ends with (``cfg.keep``), and that
    round's ``val_success``."""
    folder = out / "demonstrations"
    log = out / DEMONSTRATIONS_JSON
    if log.is_file() and json.loads(log.read_text()).get("made_by") != made_by:
        stale = out / "stale-demonstrations"
        stale.mkdir(exist_ok=True)
        target = stale / str(len(list(stale.iterdir())))
        target.mkdir()
        for old in (folder, log):
            if old.exists():
                old.rename(target / old.name)
        print(
            f"{out}: demonstrations made by other code or settings moved to {target}",
            file=sys.stderr,
        )
    folder.mkdir(parents=True, exist_ok=True)
    history = _resume(model, folder, log)
    progress(sum(cfg.episodes_per_round if r["round"] else cfg.expert_episodes for r in history))
    data = None
    if history:  # the logged rounds' samples (a kill between the two writes left more)
        saved, logged = np.load(folder / "data.npz"), history[-1]["samples"]
        data = (saved["observations"][:logged], saved["actions"][:logged])
    settings = cfg.clone_settings
    for round_ in range(len(history), cfg.rounds + 1):
        started = time.perf_counter()
        rng = np.random.default_rng([seed, round_])
        episodes = cfg.expert_episodes if round_ == 0 else cfg.episodes_per_round
        driver = None if round_ == 0 else model
        venv.seed(round_seed(seed, round_))
        obs, actions, steps, decisions = collect(
            venv, episodes, driver, cfg.every_control_step, progress
        )
        data = (
            (obs, actions)
            if data is None
            else tuple(
                np.concatenate([old, new]) for old, new in zip(data, (obs, actions), strict=True)
            )
        )
        loss = clone(model.policy, *data, stop_index, settings, rng)
        successes, returns = evaluate()
        before = history[-1] if history else {"control_steps": 0, "decisions": 0, "wall_time_s": 0}
        history.append(
            {
                "round": round_,
                "control_steps": before["control_steps"] + steps,
                "decisions": before["decisions"] + decisions,
                "samples": len(data[0]),
                "wall_time_s": before["wall_time_s"] + time.perf_counter() - started,
                "loss": loss,
                "val_success": float(np.mean(successes)),
                "val_episodes": [int(s) for s in successes],
                "val_return": float(np.mean(returns)),
                "val_returns": returns,
            }
        )
        _save_round(model, folder, round_, data, log, {"made_by": made_by, "rounds": history})
        on_round(history)
    kept = kept_round(history, cfg.keep)
    if kept != history[-1]["round"]:
        _load_round(model, folder / f"round_{kept}.zip")
    per_episode = ("val_episodes", "val_returns")
    stage = {k: v for k, v in history[-1].items() if k not in per_episode}  # the stage's totals
    return {**stage, "kept_round": kept, "val_success": history[kept]["val_success"]}


def stage_episodes(cfg: DemonstrationConfig) -> int:
    """The episodes the stage drives: the expert's, then each round's learner's."""
    return cfg.expert_episodes + cfg.rounds * cfg.episodes_per_round


def round_seed(seed: int, round_: int) -> int:
    """The seed of round ``round_``'s episodes (worlds, legs, the estimators' draws): each
    round starts from its own, so a stage resumed after any round drives the episodes an
    uninterrupted one would."""
    return int(np.random.SeedSequence([seed, round_]).generate_state(1)[0])


def kept_round(history: list[dict], keep: str) -> int:
    """The round the stage ends with: the last, or the best on the validation worlds (the
    latest of equals)."""
    if keep == "last":
        return history[-1]["round"]
    return max(history, key=lambda r: (r["val_success"], r["round"]))["round"]


def read_history(out: Path) -> list[dict]:
    """The rounds logged in ``out/demonstrations.json`` (none: an empty list)."""
    path = Path(out) / DEMONSTRATIONS_JSON
    return json.loads(path.read_text())["rounds"] if path.is_file() else []


def _resume(model, folder: Path, log: Path) -> list[dict]:
    """The rounds done (their log), with the last round's policy loaded into ``model``."""
    history = read_history(log.parent)
    if history:
        _load_round(model, folder / f"round_{history[-1]['round']}.zip")
    return history


def _load_round(model, path: Path) -> None:
    """``model``'s policy replaced by the one saved in ``path``."""
    model.policy.load_state_dict(type(model).load(path, device="cpu").policy.state_dict())


def _save_round(model, folder: Path, round_: int, data: tuple, log: Path, record: dict) -> None:
    """The data set, the round's model, then the log (each atomic): a logged round implies
    its model and data."""
    buffer = io.BytesIO()
    np.savez(buffer, observations=data[0], actions=data[1])
    write_atomic(folder / "data.npz", buffer.getvalue())
    buffer = io.BytesIO()
    model.save(buffer)
    write_atomic(folder / f"round_{round_}.zip", buffer.getvalue())
    write_json(log, record)
