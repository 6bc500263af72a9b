"""A training campaign: one run per pose source and seed, in this process or as Ray tasks.

``stsf-gym train --estimators a,b --seeds N [--backend local|ray]`` trains the cross product,
each run in ``OUT/<pose source>/seed-<s>/``. A run that the same code and settings finished is
skipped (:func:`~stsf_gym.agents.training.train.train` returns its summary untouched), and an
unfinished one resumes from its last checkpoint, so a campaign killed at any point is rerun
with the same command. Locally the runs go one after another in this process (each already
uses ``n_envs`` worker processes); on Ray (the sweeps' backend,
:func:`~stsf_gym.experiments.sweep.backends.ray_runner`) they run side by side, ``n_envs`` CPUs
each, on a local instance of ``--workers`` CPUs or on a cluster (``--address``), unchanged.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from stsf_gym.experiments.cache import Crash, JobsFailed
from stsf_gym.validation import ConfigError

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
    (a progress bar, a line of output). A job that raises ends a local campaign at once (its
    checkpoint kept); on Ray the other jobs go on and the failures are raised together as
    :class:`~stsf_gym.experiments.cache.JobsFailed` once every job has finished (the command
    exits 1; a rerun retries them)."""
    done: dict[int, dict] = {}
    if backend == "local":
        if address is not None:  # as every other command: not ignored
            raise ConfigError("--address is only for --backend ray (a campaign on a cluster)")
        for index, job in enumerate(jobs):
            done[index] = train_job(job)
            if on_done is not None:
                on_done(job, done[index])
        return [done[index] for index in range(len(jobs))]
    from stsf_gym.experiments.sweep.backends import make_runner

    cpus = max(map(_cpus, jobs), default=1)
    runner = make_runner(backend, workers, address, cpus_per_job=cpus)
    numbered = [{**job, "_index": index} for index, job in enumerate(jobs)]
    failures: dict[str, str] = {}
    for job, result in runner(_numbered_job, numbered):
        index, job = job["_index"], {k: v for k, v in job.items() if k != "_index"}
        if isinstance(result, Crash) or (isinstance(result, dict) and "error" in result):
            error = result.error if isinstance(result, Crash) else result["error"]
            failures[f"{job['estimator']} seed {job['seed']}"] = error
            continue
        done[index] = result
        if on_done is not None:
            on_done(job, result)
    if failures:
        raise JobsFailed(failures, Path(jobs[0]["out"]).parent.parent, attempts=1)
    return [done[index] for index in range(len(jobs))]


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


def _numbered_job(job: Job) -> dict:
    """:func:`train_job` of a job that carries its place in the campaign (``_index``)."""
    return train_job({k: v for k, v in job.items() if k != "_index"})
