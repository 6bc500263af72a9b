"""A training campaign: one run per pose source and seed, in this process or as Ray tasks.

``stsf-gym train --estimators a,b --seeds N [--backend local|ray]`` trains the cross product,
each run in ``OUT/<pose source>/seed-<s>/``. A run that the same code and settings finished is
skipped (:func:`~stsf_gym.agents.training.train.train` returns its summary untouched), and an
unfinished one resumes from its last checkpoint, so a campaign killed at any point is rerun
with the same command: the runs are jobs of the engine
(:func:`~stsf_gym.experiments.jobs.engine.run_jobs`) that keep their own state, not its cache.
Locally the runs go one after another in this process (each already uses ``n_envs`` worker
processes); on Ray they run side by side, ``n_envs`` CPUs each, on a local instance of
``--workers`` CPUs or on a cluster (``--address``), unchanged.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.experiments.jobs.spec import JobKind

#: The arguments of :func:`~stsf_gym.agents.training.train.train` a campaign's runs share.
Job = dict[str, Any]


def campaign_jobs(shared: Job, out: Path, estimators: list[str], seeds: Iterable[int]) -> list[Job]:
    """One job per (pose source, seed): ``shared`` with its pose source, seed and folder."""
    return [
        {**shared, "estimator": estimator, "seed": seed, "out": out / estimator / f"seed-{seed}"}
        for estimator in estimators
        for seed in seeds
    ]


def train_job(job: Job) -> dict:
    """One run of the campaign: its ``train.json`` summary (a Ray task's body)."""
    from stsf_gym.agents.training.train import train

    return train(**job, progress_bar=False)


def run_campaign(
    jobs: list[Job],
    backend: str = "local",
    workers: int = 2,
    address: str | None = None,
    on_done: Callable[[Job, dict], None] | None = None,
) -> list[dict]:
    """Every job's summary, in job order. ``on_done(job, summary)`` is called as each finishes
    (a progress bar, a line of output). A run that raises is run once more (resuming from its
    checkpoint); one failing twice is raised with the others as
    :class:`~stsf_gym.experiments.jobs.cache.JobsFailed` once every job has finished (the
    command exits 1; a rerun retries them)."""
    cpus = max(map(_cpus, jobs), default=1) if backend == "ray" else 1
    local_workers = workers if backend == "ray" else 1  # a local run's envs are its processes
    # no bar of the engine's: the caller shows the runs as they finish (on_done)
    ran = run_jobs(TRAINING_RUNS, jobs, None, "", backend, local_workers, address, cpus, on_done)
    return ran.results


def _cpus(job: Job) -> int:
    """The CPUs a run keeps busy: its ``n_envs`` env processes (the hyper-parameter file's
    when the job does not set it)."""
    if job.get("n_envs"):
        return job["n_envs"]
    from stsf_gym.agents.training.hyperparams import load_hyperparams
    from stsf_gym.agents.training.train import env_id_for
    from stsf_gym.envs.generated_env import generated_label

    suite = job.get("suite")
    world = generated_label("train") if suite else job.get("world", "irl_corridor")
    env_id = env_id_for(world, job["estimator"], suite)
    hp = load_hyperparams(job["algo"], env_id, job.get("config"), job.get("overrides"), bool(suite))
    return hp.training.n_envs


def _run_name(job: Job) -> str:
    """A run's name: its pose source and seed (its folder below the campaign's)."""
    return f"{job['estimator']} seed {job['seed']}"


#: A campaign's runs as jobs of the engine (each resumes from its own folder).
TRAINING_RUNS = JobKind(train_job, _run_name)
