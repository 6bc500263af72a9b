"""What a training run records beside TensorBoard: per-episode and per-evaluation CSV files
(they survive a resume, unlike SB3's own logs) and the learning-curve figure drawn from them."""

from __future__ import annotations

import csv
import time
from pathlib import Path

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from stsf_gym.io import save_figure

EPISODES_CSV = "episodes.csv"  # timesteps, reward, length, success of each training episode
EVAL_CSV = "eval.csv"  # timesteps, mean reward, success rate of each evaluation
SMOOTHING = 20  # training episodes in the rolling mean of the curves


def append_row(path: Path, header: list[str], row: list) -> None:
    """Append ``row`` to the CSV file ``path``, writing ``header`` first when the file is new."""
    new = not path.is_file()
    with path.open("a", newline="") as f:
        writer = csv.writer(f)
        if new:
            writer.writerow(header)
        writer.writerow(row)


def read_rows(path: Path) -> np.ndarray:
    """The CSV's numbers as a 2-D array (no rows: shape (0, columns))."""
    if not path.is_file():
        return np.zeros((0, 4))
    with path.open() as f:
        rows = list(csv.reader(f))[1:]
    return np.array(rows, dtype=float).reshape(len(rows), -1)


def drop_rows_after(path: Path, timesteps: int) -> None:
    """Forget episodes logged after the checkpoint a resumed run starts from."""
    if not path.is_file():
        return
    with path.open() as f:
        header, *rows = list(csv.reader(f))
    with path.open("w", newline="") as f:
        csv.writer(f).writerows([header, *(r for r in rows if float(r[0]) <= timesteps)])


class EpisodeLog(BaseCallback):
    """Appends every finished training episode (from ``Monitor``'s ``info["episode"]``) to
    ``episodes.csv`` and keeps the model's ``stsf_meta["wall_time_s"]`` current, so that each
    checkpoint carries the training time spent so far."""

    def __init__(self, out: Path, wall_time_before: float = 0.0) -> None:
        super().__init__()
        self.path = Path(out) / EPISODES_CSV
        self.wall_time_before = wall_time_before

    def _on_training_start(self) -> None:
        self.started = time.perf_counter()

    def _on_step(self) -> bool:
        elapsed = time.perf_counter() - self.started
        self.model.stsf_meta["wall_time_s"] = self.wall_time_before + elapsed
        for info in self.locals["infos"]:
            episode = info.get("episode")
            if episode is not None:
                success = int(info.get("is_success", False))
                row = [self.num_timesteps, episode["r"], episode["l"], success]
                append_row(self.path, ["timesteps", "reward", "length", "success"], row)
        return True


class EvalLog(BaseCallback):
    """Run by ``EvalCallback`` after each evaluation: appends its result to ``eval.csv``."""

    def __init__(self, out: Path) -> None:
        super().__init__()
        self.path = Path(out) / EVAL_CSV

    def _on_step(self) -> bool:
        evaluation = self.parent
        rewards = evaluation.evaluations_results[-1]
        successes = evaluation.evaluations_successes[-1] if evaluation.evaluations_successes else []
        row = [self.num_timesteps, float(np.mean(rewards)), float(np.mean(successes or [0.0]))]
        append_row(self.path, ["timesteps", "mean_reward", "success_rate"], row)
        return True


def last_evaluation(out: Path) -> dict | None:
    """The last evaluation of the run in ``out`` (timesteps, mean reward, success rate), or None."""
    rows = read_rows(Path(out) / EVAL_CSV)
    if not len(rows):
        return None
    timesteps, reward, success = rows[-1]
    return {"timesteps": int(timesteps), "mean_reward": reward, "success_rate": success}


def rolling_mean(values: np.ndarray, window: int) -> np.ndarray:
    """Mean of each value and up to ``window - 1`` before it (fewer at the start)."""
    sums = np.concatenate([[0.0], np.cumsum(values)])
    index = np.arange(1, len(values) + 1)
    first = np.maximum(index - window, 0)
    return (sums[index] - sums[first]) / (index - first)


def plot_learning_curve(out: Path, title: str) -> Path:
    """Episode reward and success rate against timesteps: training (rolling mean of
    ``SMOOTHING`` episodes) and deterministic evaluations."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out)
    episodes, evaluations = read_rows(out / EPISODES_CSV), read_rows(out / EVAL_CSV)
    fig, (ax_r, ax_s) = plt.subplots(1, 2, figsize=(11, 4))
    if len(episodes):
        ax_r.plot(episodes[:, 0], rolling_mean(episodes[:, 1], SMOOTHING), label="training")
        ax_s.plot(episodes[:, 0], rolling_mean(episodes[:, 3], SMOOTHING), label="training")
    if len(evaluations):
        ax_r.plot(evaluations[:, 0], evaluations[:, 1], "o-", label="evaluation")
        ax_s.plot(evaluations[:, 0], evaluations[:, 2], "o-", label="evaluation")
    ax_r.set(xlabel="timesteps", ylabel="episode reward", title=f"{title}: reward")
    ax_s.set(xlabel="timesteps", ylabel="success rate", ylim=(-0.05, 1.05), title="goal reached")
    for ax in (ax_r, ax_s):
        ax.grid(alpha=0.3)
        if ax.lines:  # nothing finished yet: no legend
            ax.legend()
    try:
        return save_figure(fig, out / "learning_curve.png")
    finally:
        plt.close(fig)
