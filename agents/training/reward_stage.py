"""The stage that learns from the env's reward: PPO (or SAC) on the pose source's own
estimate, alone (plain RL, from :func:`~stsf_gym.agents.training.stop_prior.set_stop_prior`'s
prior) or after the demonstrations (fine-tuning the clone,
:class:`~stsf_gym.agents.training.finetune.FinetunePPO`), checkpointed after every update."""

from __future__ import annotations

import time
import warnings
from pathlib import Path

from stable_baselines3.common.callbacks import CallbackList
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
from stable_baselines3.common.vec_env import VecEnv
from tqdm import tqdm

from stsf_gym.agents.training.checkpoints import (
    AtomicCheckpoint,
    SaveBest,
    save_checkpoint,
    save_model,
)
from stsf_gym.agents.training.finetune import FinetunePPO, FreshRollouts, widen_exploration
from stsf_gym.agents.training.progress import RewardProgress
from stsf_gym.agents.training.resumed_eval import ResumableEvalCallback
from stsf_gym.agents.training.settings import RunSettings
from stsf_gym.agents.training.training_envs import EVAL_SEED_OFFSET
from stsf_gym.agents.training.training_log import EpisodeLog, EvalLog
from stsf_gym.agents.training_folder import CLONE


def guard_the_clone(model: FinetunePPO, run: RunSettings, out: Path) -> None:
    """The fine-tuning's guards (:class:`FinetunePPO`): its learning rate, and the clone,
    saved when the stage first starts (a resumed stage reads it back); the exploration
    widened before the first update (:func:`widen_exploration`)."""
    settings = run.hp.finetune
    path = out / CLONE
    if not path.is_file():
        save_model(model, path)
    if model.num_timesteps == 0 and settings.exploration_std is not None:
        widen_exploration(model.policy, settings.exploration_std)
    clone = type(model).load(path, device="cpu").policy
    if settings.learning_rate is not None:
        model.learning_rate = settings.learning_rate
        model._setup_lr_schedule()
    model.guard(clone, settings.value_warmup_steps, settings.clone_kl_coef)


class SameWorldsEval(ResumableEvalCallback):
    """Evaluation on the same val worlds each time (the env reseeded with ``seed``), as each
    demonstration round is evaluated, so a learning curve's points are paired; at the run's
    timesteps, resumed or not (:class:`ResumableEvalCallback`)."""

    def __init__(self, seed: int, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.seed = seed

    def _on_step(self) -> bool:
        if self.eval_freq > 0 and self.n_calls % self.eval_freq == 0:
            self.eval_env.seed(self.seed)
        return super()._on_step()


def callbacks(model, run: RunSettings, out: Path, eval_env: VecEnv, bar: tqdm) -> list:
    """Logging, checkpoints, evaluation on the val worlds and the stage's progress ``bar``;
    and rollouts that start afresh when fine-tuning (:class:`FreshRollouts`)."""
    cfg = run.hp.training
    return [
        EpisodeLog(out, model.stsf_meta["wall_time_s"]),
        RewardProgress(bar),
        *([FreshRollouts(run.seed)] if run.finetuning else []),
        AtomicCheckpoint(cfg.checkpoint_freq, run.n_envs, out),
        SameWorldsEval(
            run.seed + EVAL_SEED_OFFSET,
            eval_env,
            out=out,
            n_eval_episodes=cfg.n_eval_episodes,
            eval_freq=max(cfg.eval_freq // run.n_envs, 1),
            log_path=str(out / "eval"),
            callback_on_new_best=SaveBest(out),
            deterministic=True,
            callback_after_eval=EvalLog(out),
            verbose=0,
        ),
    ]


def learn_from_reward(
    model, run: RunSettings, out: Path, envs: tuple[VecEnv, VecEnv], bar: tqdm | None
) -> float:
    """Learn until the reward budget; return the session's seconds. Ctrl-C saves SAC's
    checkpoint (PPO's last update is saved already) and is raised again."""
    train_env, eval_env = envs
    start = model.num_timesteps
    if run.finetuning:
        guard_the_clone(model, run, out)
    train_env.seed(run.seed + start)
    started = time.perf_counter()
    if run.reward_steps > start:
        try:
            with warnings.catch_warnings():
                # one evaluation env needs no worker process: the vec env types differ
                warnings.filterwarnings("ignore", "Training and eval env are not of the same")
                model.learn(
                    run.reward_steps - start,
                    callback=CallbackList(callbacks(model, run, out, eval_env, bar)),
                    reset_num_timesteps=False,
                    tb_log_name=run.algo,
                )
        except KeyboardInterrupt:
            if not isinstance(model, OnPolicyAlgorithm):  # PPO: its last update is saved
                save_checkpoint(model, out)
            raise
    return time.perf_counter() - started
