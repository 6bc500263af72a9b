"""``stsf-gym train``: an agent driving on one pose source, in stages, resumable.

The stages, as rl-baselines3-zoo's ``ExperimentManager`` reads: settings resolved and checked
(:func:`~stsf_gym.agents.training.settings.resolve_run`, nothing written before), envs made
(:mod:`~stsf_gym.agents.training.training_envs`), the model resumed from its newest checkpoint
or created (:mod:`~stsf_gym.agents.training.checkpoints`), the demonstrations (cloning and
DAgger rounds, :mod:`~stsf_gym.agents.demonstrations.dagger`), learning from reward
(:mod:`~stsf_gym.agents.training.reward_stage`), and the model and summary saved. ``algo``
records what ran (``dagger``, ``dagger+ppo``, ``ppo``, ``sac``) in ``train.json`` and the
model's metadata.

``OUT`` receives ``checkpoints/``, ``tb/`` (TensorBoard, every stage), ``monitor/``,
``eval/`` and ``best/`` (the best evaluated model), ``demonstrations/`` and
``demonstrations.json``, ``finetune/clone.zip``, ``episodes.csv``, ``eval.csv``,
``learning_curve.png`` (redrawn after each round and at the end), ``model.zip`` and
``train.json``. With ``suite`` the agent trains on a benchmark suite's train worlds under its
task and is evaluated on the suite's ``val`` worlds, never on the benchmark's ``test`` ones.
Rerunning with the same ``OUT`` continues from the last round or checkpoint and ends at exactly
the timesteps asked for (whole updates: :func:`~stsf_gym.agents.training.hyperparams.
check_timesteps`); a run that the same code and settings finished is returned untouched.
"""

from __future__ import annotations

import os
from functools import partial
from pathlib import Path

from tqdm import tqdm

from stsf_gym.agents.demonstrations.dagger import run_demonstrations, stage_episodes
from stsf_gym.agents.model_files import META_KEY
from stsf_gym.agents.rl.residual import start_as_follower
from stsf_gym.agents.training.checkpoints import (
    finished_summary,
    latest_checkpoint,
    resumable_steps,
    resume,
    save_atomic,
    save_checkpoint,
    save_model,
)
from stsf_gym.agents.training.finetune import FinetunePPO
from stsf_gym.agents.training.hyperparams import algorithm_class, policy_kwargs_for_sb3
from stsf_gym.agents.training.preflight import check_out, check_seeds, run_kind
from stsf_gym.agents.training.progress import log_round, stage_bars
from stsf_gym.agents.training.replaced_runs import keep_replaced_run
from stsf_gym.agents.training.reward_stage import learn_from_reward
from stsf_gym.agents.training.settings import RunSettings, resolve_run
from stsf_gym.agents.training.stop_prior import set_stop_prior
from stsf_gym.agents.training.training_envs import (
    EVAL_SEED_OFFSET,
    check_training_env,
    env_id_for,
    make_training_env,
    make_vec_env,
    note_workers_code,
    val_outcomes,
)
from stsf_gym.agents.training.training_log import last_evaluation, plot_learning_curve
from stsf_gym.io import write_json
from stsf_gym.results.code_identity import code_version
from stsf_gym.results.machine_speed import reference_ms

__all__ = [
    "EVAL_SEED_OFFSET", "env_id_for", "latest_checkpoint", "make_training_env", "save_atomic",
    "train",
]  # fmt: skip


def create_model(run: RunSettings, out: Path, train_env):
    """A fresh model; the residual learner's mean correction starts from 0
    (:func:`start_as_follower`); plain RL's STOP entry from its prior (:func:`set_stop_prior`)
    unless a false stop on its legs goes on (the run's ``declaration``)."""
    cfg = run.hp.training
    cls = FinetunePPO if run.finetuning else algorithm_class(run.algo)
    model = cls(
        cfg.policy,
        train_env,
        policy_kwargs=policy_kwargs_for_sb3(cfg.policy_kwargs),
        tensorboard_log=str(out / "tb"),
        seed=run.seed,
        device="cpu",
        **run.hp.algo_kwargs,
    )
    setattr(model, META_KEY, dict(run.meta))
    if run.residual is not None:  # before any update, it drives as the follower does
        start_as_follower(model.policy, run.residual)
    layout = train_env.get_attr("action_layout", [0])[0]
    goes_on = run.declaration is not None and run.declaration.goes_on
    if (
        not (run.demonstrating or goes_on)
        and "stop" in layout
        and hasattr(model.policy, "action_net")
    ):
        set_stop_prior(model.policy, layout.index("stop"), cfg.initial_stop_probability)
    return model


def demonstrate(model, run: RunSettings, out: Path, eval_env, bar: tqdm) -> None:
    """The demonstration stage (:func:`run_demonstrations`) in envs whose states the expert
    labels; the learner evaluated after each round on the val worlds, each round drawn into
    the learning curve and TensorBoard."""
    cfg, title = run.hp.demonstrations, curve_title(run)
    teacher = cfg.teacher_pose  # the follower on the truth, or on the student's estimate
    venv = make_vec_env(run.n_envs, out, "demonstrations", expert=teacher, **run.env_spec(True))
    layout = venv.get_attr("action_layout", [0])[0]
    evaluate = partial(
        val_outcomes, model, eval_env, run.hp.training.n_eval_episodes, run.seed + EVAL_SEED_OFFSET
    )

    def on_round(history: list[dict]) -> None:
        last = history[-1]
        bar.set_postfix(round=last["round"], val_success=f"{last['val_success']:.2f}")
        log_round(out, last)
        plot_learning_curve(out, title)

    try:
        stop = layout.index("stop") if "stop" in layout else None
        made_by = model.stsf_meta["demonstrations_made_by"]
        stage = run_demonstrations(
            model, venv, cfg, stop, out, evaluate, run.seed, made_by, bar.update, on_round
        )
        note_workers_code(venv)
    finally:
        bar.close()
        venv.close()
    model.stsf_meta["demonstrations"] = stage
    model.stsf_meta["wall_time_s"] = stage["wall_time_s"]  # the reward stage has not started
    model.stsf_meta["control_steps"] = stage["control_steps"]


def curve_title(run: RunSettings) -> str:
    """The learning curve's title: what ran, on which pose source."""
    return f"{run.algo} on {run.estimator}"


def save_run(model, run: RunSettings, out: Path, start: int, session: float, machine: dict):
    """The final model, checkpoint and ``train.json`` (the run's summary, returned)."""
    if model.num_timesteps > start:
        save_checkpoint(model, out)
    # the code as the run loaded it by now, here and in the env processes
    model.stsf_meta["provenance"] = {**model.stsf_meta["provenance"], "stsf_gym": code_version()}
    save_model(model, out / "model.zip")
    summary = {
        **{k: v for k, v in model.stsf_meta.items() if k != "wall_time_s"},
        "timesteps": model.num_timesteps,
        "resumed_from": start,
        "n_envs": run.n_envs,
        "wall_time_s": model.stsf_meta["wall_time_s"],
        "session_wall_time_s": session,
        "steps_per_second": (model.num_timesteps - start) / session if session > 0 else None,
        # the machine's speed beside the times (stsf-gym bench's reference workload, ms)
        "machine": {**machine, "reference_ms_after": reference_ms()},
        "last_evaluation": last_evaluation(out),
        "model": str(out / "model.zip"),
        "learning_curve": str(plot_learning_curve(out, curve_title(run))),
    }
    write_json(out / "train.json", summary)
    return summary


def train(
    algo: str,
    estimator: str,
    out: str | Path,
    timesteps: int | None = None,
    seed: int = 0,
    world: str = "irl_corridor",
    config: str | Path | None = None,
    overrides: dict | None = None,
    n_envs: int | None = None,
    progress_bar: bool = True,
    suite: str | None = None,
) -> dict:
    """Train (or continue training) ``algo`` (``dagger``, ``dagger+ppo``, ``ppo``, ``sac``:
    :mod:`~stsf_gym.agents.training.settings`) until its reward budget (``timesteps``, or the
    file's); return the summary in train.json. With ``suite`` the agent trains on the suite's
    train worlds under its task and is evaluated on its ``val`` worlds."""
    check_seeds(seed, 1)
    run = resolve_run(algo, estimator, timesteps, seed, world, config, overrides, n_envs, suite)
    out = Path(out)
    check_out(out, run_kind(run.algo, estimator, world, suite))  # another kind's work: refused
    finished = finished_summary(out, run.meta["made_by"], run.reward_steps)
    if finished is not None:  # a campaign's rerun: this run is done, its files stay untouched
        return finished
    check_training_env(run.world, run.estimator, run.train_env, run.seed)  # before any output
    keep_replaced_run(out, run.meta["made_by"])  # one finished by other code or settings: kept
    episodes = stage_episodes(run.hp.demonstrations) if run.demonstrating else 0
    resumed = resumable_steps(out, run.meta["made_by"])
    bars = stage_bars(episodes, run.reward_steps, run.algo, progress_bar, resumed)  # drawn at once
    try:
        return run_stages(run, out, bars)
    finally:
        for bar in bars:
            if bar is not None:
                bar.close()


def run_stages(run: RunSettings, out: Path, bars: tuple) -> dict:
    """The stages after the settings: envs, resume or create, demonstrate, learn from reward,
    save (see the module)."""
    import torch

    torch.set_num_threads(1)
    out.mkdir(parents=True, exist_ok=True)
    machine = {"reference_ms_before": reference_ms(), "load_average_before": os.getloadavg()}
    train_env = make_vec_env(run.n_envs, out, "train", **run.env_spec(True))
    eval_env = make_vec_env(1, out, "eval", **run.env_spec(False))
    eval_env.seed(run.seed + EVAL_SEED_OFFSET)
    try:
        cls = FinetunePPO if run.finetuning else algorithm_class(run.algo)
        model = resume(cls, out, run.meta, train_env) or create_model(run, out, train_env)
        if run.demonstrating and model.num_timesteps == 0:
            demonstrate(model, run, out, eval_env, bars[0])
        elif run.demonstrating:  # resumed after the demonstrations
            bars[0].update(bars[0].total - bars[0].n)
        start = model.num_timesteps
        session = learn_from_reward(model, run, out, (train_env, eval_env), bars[1])
        note_workers_code(train_env)
    finally:
        train_env.close()
        eval_env.close()
    return save_run(model, run, out, start, session, machine)
