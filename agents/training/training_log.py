"""What a training run records beside TensorBoard: per-episode and per-evaluation CSV files
(they survive a resume, unlike SB3's own logs) and the learning curve drawn from them and from
the demonstration rounds (``demonstrations.json``): val success and return against env
steps (control steps, 0.1 s each, of every stage) and against wall time."""

from __future__ import annotations

import csv
import io
import json
import os
import time
from pathlib import Path

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from stsf_gym.agents.demonstrations.dagger import read_history
from stsf_gym.io import save_figure, write_atomic, write_json

EPISODES_CSV = "episodes.csv"  # timesteps, reward, length, success, control steps
EVAL_CSV = "eval.csv"  # timesteps, mean reward, success rate, control steps, wall time (s)
EVALUATIONS_JSON = "evaluations.json"  # each evaluation's episodes: successes and returns
LEARNING_CURVE = "learning_curve.png"
SMOOTHING = 20  # training episodes in the rolling mean of the curves


def append_row(path: Path, header: list[str], row: list) -> None:
    """Append ``row`` to the CSV file ``path``, writing ``header`` first when the file is new;
    a write that fails (a full disk) leaves the file as it was, no row cut short."""
    new = not path.is_file()
    size = 0 if new else path.stat().st_size
    lines = io.StringIO()
    writer = csv.writer(lines)
    if new:
        writer.writerow(header)
    writer.writerow(row)
    try:
        with path.open("a", newline="") as f:
            f.write(lines.getvalue())
    except OSError:
        if path.is_file():
            os.truncate(path, size)
        raise


def read_rows(path: Path) -> np.ndarray:
    """The CSV's numbers as a 2-D array (no rows, a header alone included: shape (0, columns))."""
    if not path.is_file():
        return np.zeros((0, 4))
    with path.open() as f:
        header, *rows = list(csv.reader(f)) or [[]]
    return np.array(rows, dtype=float).reshape(len(rows), len(header))


def read_evaluations(out: Path) -> list[dict]:
    """The reward stage's evaluations in ``out`` (:class:`EvalLog`), oldest first."""
    path = Path(out) / EVALUATIONS_JSON
    return json.loads(path.read_text()) if path.is_file() else []


def drop_rows_after(path: Path, timesteps: int) -> None:
    """Forget episodes (or evaluations) logged after the checkpoint a resumed run starts from."""
    if path.name == EVALUATIONS_JSON:
        kept = [e for e in read_evaluations(path.parent) if e["timesteps"] <= timesteps]
        write_json(path, kept)
        return
    if not path.is_file():
        return
    with path.open() as f:
        header, *rows = list(csv.reader(f))
    kept = io.StringIO()  # written atomically: a full disk leaves the file as it was
    csv.writer(kept).writerows([header, *(r for r in rows if float(r[0]) <= timesteps)])
    write_atomic(path, kept.getvalue())


class EpisodeLog(BaseCallback):
    """Appends every finished training episode (from ``Monitor``'s ``info["episode"]``) to
    ``episodes.csv`` and keeps the model's ``stsf_meta`` ``wall_time_s`` and ``control_steps``
    (every stage's) current, so that each checkpoint carries the time and steps so far."""

    def __init__(self, out: Path, wall_time_before: float = 0.0) -> None:
        super().__init__()
        self.path = Path(out) / EPISODES_CSV
        self.wall_time_before = wall_time_before

    def _on_training_start(self) -> None:
        self.started = time.perf_counter()

    def _on_step(self) -> bool:
        elapsed = time.perf_counter() - self.started
        meta = self.model.stsf_meta
        meta["wall_time_s"] = self.wall_time_before + elapsed
        infos = self.locals["infos"]
        meta["control_steps"] = meta.get("control_steps", 0) + sum(
            info.get("control_steps", 1) for info in infos
        )
        for info in infos:
            episode = info.get("episode")
            if episode is not None:
                success = int(info.get("is_success", False))
                row = [self.num_timesteps, episode["r"], episode["l"], success]
                header = ["timesteps", "reward", "length", "success", "control_steps"]
                append_row(self.path, header, [*row, meta["control_steps"]])
        return True


class EvalLog(BaseCallback):
    """Run by ``EvalCallback`` after each evaluation: appends its means to ``eval.csv`` and its
    episodes (success, return) to ``evaluations.json``, with the env steps and time so far."""

    def __init__(self, out: Path) -> None:
        super().__init__()
        self.path = Path(out) / EVAL_CSV

    def _on_step(self) -> bool:
        evaluation = self.parent
        rewards = evaluation.evaluations_results[-1]
        successes = evaluation.evaluations_successes[-1] if evaluation.evaluations_successes else []
        meta = self.model.stsf_meta
        row = [self.num_timesteps, float(np.mean(rewards)), float(np.mean(successes or [0.0]))]
        header = ["timesteps", "mean_reward", "success_rate", "control_steps", "wall_time_s"]
        steps, wall = meta.get("control_steps", 0), meta["wall_time_s"]
        append_row(self.path, header, [*row, steps, wall])
        record = {"timesteps": self.num_timesteps, "control_steps": steps, "wall_time_s": wall}
        record |= {
            "val_episodes": [int(s) for s in successes],
            "val_returns": [float(r) for r in rewards],
        }
        write_json(
            self.path.with_name(EVALUATIONS_JSON), [*read_evaluations(self.path.parent), record]
        )
        return True


def last_evaluation(out: Path) -> dict | None:
    """The last evaluation of the run in ``out`` (timesteps, mean reward, success rate), or None."""
    rows = read_rows(Path(out) / EVAL_CSV)
    if not len(rows):
        return None
    timesteps, reward, success = rows[-1][:3]
    return {"timesteps": int(timesteps), "mean_reward": reward, "success_rate": success}


def rolling_mean(values: np.ndarray, window: int) -> np.ndarray:
    """Mean of each value and up to ``window - 1`` before it (fewer at the start)."""
    sums = np.concatenate([[0.0], np.cumsum(values)])
    index = np.arange(1, len(values) + 1)
    first = np.maximum(index - window, 0)
    return (sums[index] - sums[first]) / (index - first)


def curve_points(out: Path) -> list[dict]:
    """The run's evaluations on its val worlds (the same worlds each time), in order: each
    demonstration round's, then the reward stage's: ``stage``, ``control_steps``,
    ``wall_time_s``, ``val_episodes`` (0/1 each), ``val_returns``, and their means."""
    keys = ("control_steps", "wall_time_s", "val_episodes", "val_returns")
    staged = [("demonstrations", r) for r in read_history(out) if "val_returns" in r]
    staged += [("reward", e) for e in read_evaluations(out)]
    return [
        {"stage": stage, **{k: record[k] for k in keys}}
        | {
            "val_success": float(np.mean(record["val_episodes"])),
            "val_return": float(np.mean(record["val_returns"])),
        }
        for stage, record in staged
    ]


def plot_learning_curve(out: Path, title: str) -> Path:
    """Val success and return against env steps and wall time (:func:`curve_points`), with
    the training episodes' return (rolling mean of ``SMOOTHING``) beside them."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out)
    points, episodes = curve_points(out), read_rows(out / EPISODES_CSV)
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex="col", sharey="row")
    styles = {"demonstrations": ("s--", "demonstration rounds"), "reward": ("o-", "from reward")}
    for stage, (style, label) in styles.items():
        mine = [p for p in points if p["stage"] == stage]
        if not mine:
            continue
        steps = [p["control_steps"] for p in mine]
        minutes = [p["wall_time_s"] / 60 for p in mine]
        for row, key in enumerate(("val_success", "val_return")):
            values = [p[key] for p in mine]
            axes[row, 0].plot(steps, values, style, label=label)
            axes[row, 1].plot(minutes, values, style, label=label)
    if len(episodes) and episodes.shape[1] >= 5:
        training = rolling_mean(episodes[:, 1], SMOOTHING)
        axes[1, 0].plot(episodes[:, 4], training, color="0.6", label="training episodes")
    axes[0, 0].set(ylabel="val success", ylim=(-0.05, 1.05), title=f"{title}: val worlds")
    axes[1, 0].set(ylabel="return", xlabel="env steps (control steps, 0.1 s)")
    axes[1, 1].set(xlabel="wall time (min)")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        if ax.lines:  # nothing evaluated yet: no legend
            ax.legend(fontsize="small")
    try:
        return save_figure(fig, out / LEARNING_CURVE)
    finally:
        plt.close(fig)
