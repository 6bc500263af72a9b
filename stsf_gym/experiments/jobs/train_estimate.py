"""What ``stsf-gym train`` will do, said before it starts, with its time from speeds measured
here: the reward decisions still to run (a run resumed from its newest checkpoint counts only
those after it) over the decisions per second measured on the same training, plus the
demonstration episodes still to drive over the seconds per episode measured (see
:func:`~stsf_gym.experiments.jobs.estimate.record_speed`). With no speed measured here it says
so; a finished run (:func:`record_run`) adds what it measured.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from stsf_gym.agents.demonstrations.dagger import stage_episodes
from stsf_gym.agents.training.checkpoints import finished_summary, resumable_steps
from stsf_gym.agents.training.settings import RunSettings, resolve_run
from stsf_gym.agents.training.training_envs import check_training_env
from stsf_gym.experiments.jobs.estimate import duration, record_speed, speed_estimate, work_key


@dataclass(frozen=True)
class RunLeft:
    """What one training run still has to do."""

    run: RunSettings
    episodes: int  # demonstration episodes still to drive
    decisions: int  # reward decisions still to run
    done: int  # reward decisions already run (its newest checkpoint's)


def run_left(job: dict) -> RunLeft:
    """``job``'s settings (the keyword arguments of ``train``) and the work left in its folder:
    none when finished; after a checkpoint of the same settings, the decisions after it."""
    run = resolve_run(
        job["algo"], job["estimator"], job["timesteps"], job["seed"], job["world"],
        job["config"], job["overrides"], job["n_envs"], job["suite"],
    )  # fmt: skip
    out, made_by = Path(job["out"]), run.meta["made_by"]
    if finished_summary(out, made_by, run.reward_steps) is not None:
        return RunLeft(run, 0, 0, run.reward_steps)
    done = min(resumable_steps(out, made_by), run.reward_steps)
    episodes = stage_episodes(run.hp.demonstrations) if run.demonstrating and not done else 0
    return RunLeft(run, episodes, run.reward_steps - done, done)


def plan(jobs: list[dict], workers: int) -> tuple[str, list[RunLeft]]:
    """What training will do (after the checks each run makes before any output, so bad input
    is still refused first): each run's stages, then the work left and its time; and each
    job's :class:`RunLeft`."""
    lefts = [run_left(job) for job in jobs]
    first = lefts[0].run
    check_training_env(first.world, first.estimator, first.train_env, first.seed)
    episodes = stage_episodes(first.hp.demonstrations) if first.demonstrating else 0
    stages = [f"{episodes} demonstration episodes"] if episodes else []
    stages += [f"{first.reward_steps} decisions learning from reward"] if first.reward_steps else []
    each = f"{first.algo}: {' then '.join(stages) or 'nothing to train'} each"
    return f"train: {len(jobs)} run(s) of {each}\n" + time_line(jobs, lefts, workers), lefts


def time_line(jobs: list[dict], lefts: list[RunLeft], workers: int) -> str:
    """The runs with work left, that work, and its time on ``workers`` processes."""
    todo = [(job, left) for job, left in zip(jobs, lefts, strict=True) if _has_work(left)]
    if not todo:
        return f"train: all {len(jobs)} run(s) already done"
    slots = max(1, min(workers, len(todo)))
    decisions, done = sum(x.decisions for _, x in todo), sum(x.done for _, x in todo)
    work = [f"{decisions:,} decisions"] if decisions else []
    work[:] = [f"{work[0]} ({done:,} already done, resumed)"] if work and done else work
    episodes = sum(x.episodes for _, x in todo)
    work += [f"{episodes} demonstration episodes"] if episodes else []
    head = f"train: {len(todo)} run(s) to run on {slots} process(es): {' and '.join(work)}"
    seconds, said = 0.0, dict[str, None]()  # said: where each speed was measured, once
    for job, left in todo:
        for units, unit in ((left.decisions, "decision"), (left.episodes, "episode")):
            if not units:
                continue
            found = speed_estimate(
                speed_desc(left.run, unit), speed_key(job, left.run), units, unit
            )
            if found is None:
                return f"{head}; no speed measured here yet: the bar's ETA follows the {unit}s"
            seconds += found[0]
            said[found[1]] = None
    return f"{head}: about {duration(seconds / slots)} ({'; '.join(said)})"


def record_run(job: dict, left: RunLeft, summary: dict) -> None:
    """Keep the speeds a run that had work left measured: its decisions over the reward stage's
    seconds in this session, its demonstration episodes over the stage's seconds."""
    if left.decisions:
        ran = summary["timesteps"] - summary["resumed_from"]
        seconds = summary["session_wall_time_s"]
        record_speed(speed_desc(left.run, "decision"), speed_key(job, left.run), ran, seconds)
    stage = summary.get("demonstrations")
    if left.episodes and isinstance(stage, dict):
        desc = speed_desc(left.run, "episode")
        record_speed(desc, speed_key(job, left.run), left.episodes, stage["wall_time_s"])


def speed_desc(run: RunSettings, unit: str) -> str:
    """Where a training's speed in ``unit`` is kept: per algorithm and suite (or world)."""
    return f"train {run.algo} {run.suite or run.world}: {unit}s"


def speed_key(job: dict, run: RunSettings) -> str:
    """The training's work apart from its seeds, folder and budget (they leave its speed):
    the command's settings and the hyper-parameters they resolve to, so a changed config file
    (a residual that decides near the goals only) is other work."""
    settings = {k: v for k, v in job.items() if k != "timesteps"}
    return work_key([{**settings, "resolved": _without_budget(run.meta["hyperparams"])}])


def _without_budget(settings: object) -> object:
    """``settings`` with every ``timesteps`` entry left out, at any depth."""
    if not isinstance(settings, dict):
        return settings
    return {k: _without_budget(v) for k, v in settings.items() if k != "timesteps"}


def _has_work(left: RunLeft) -> bool:
    return bool(left.episodes or left.decisions)
