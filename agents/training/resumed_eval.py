"""Evaluations during RL at the same timesteps whether a run was resumed or not.

stable-baselines3's ``EvalCallback`` evaluates every ``eval_freq`` of its own calls, counted
from the start of this ``learn``: a run resumed at 256 timesteps (2 envs, ``eval_freq`` 256
calls) evaluates at 768, 1280, 1792 where an uninterrupted one evaluates at 512, 1024, 1536,
2048. :class:`ResumableEvalCallback` counts its calls from the model's timesteps instead, and
takes the best mean reward of the evaluations logged before the resume (``eval.csv``), so the
best model kept is the one an uninterrupted run keeps.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from stable_baselines3.common.callbacks import EvalCallback

from stsf_gym.agents.training.training_log import EVAL_CSV, read_rows


class ResumableEvalCallback(EvalCallback):
    """``EvalCallback`` on the run's timesteps; ``out`` the training folder (its
    ``eval.csv``, already cut back to the checkpoint a resumed run starts from)."""

    def __init__(self, *args, out: Path, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.out = Path(out)

    def _on_training_start(self) -> None:
        super()._on_training_start()
        # calls an uninterrupted run would have made by now: one per vector step
        self.n_calls = self.model.num_timesteps // self.model.get_env().num_envs
        logged = read_rows(self.out / EVAL_CSV)
        if len(logged):  # columns: timesteps, mean reward, success rate
            self.best_mean_reward = float(np.max(logged[:, 1]))
