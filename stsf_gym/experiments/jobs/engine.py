"""One way every command runs its jobs: :func:`run_jobs`.

Evaluate, compare, demo, the sweep, the benchmark, the accuracy curve, Table I, the videos and
the training campaign each make their own list of jobs and write their own report; between the
two, :func:`run_jobs` forgets the failures a rerun must redo, resolves every job's
configuration once, runs the jobs still to do on the chosen backend (local processes or Ray)
and stores each result as it finishes (one SQLite file per run,
:mod:`~stsf_gym.experiments.jobs.store`). The code its workers loaded is noted into the run
current when it is called (:class:`~stsf_gym.results.run_context.RunContext`: the CLI's
command), which the report's provenance then reads.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from stsf_gym.experiments.jobs.backends import make_runner
from stsf_gym.experiments.jobs.cache import run_cached
from stsf_gym.experiments.jobs.spec import JobKind, failed
from stsf_gym.experiments.jobs.store import delete_rows, open_store, read_rows
from stsf_gym.results.run_context import current_run


@dataclass(frozen=True)
class Ran:
    """What :func:`run_jobs` returns: each job's result in job order, and each job's resolved
    configuration by key (what a report's provenance records)."""

    results: list
    configs: dict[str, Mapping]


def run_jobs(
    kind: JobKind,
    jobs: list[dict],
    store: str | Path | None,
    desc: str = "jobs",
    backend: str = "local",
    workers: int = 2,
    address: str | None = None,
    cpus_per_job: int = 1,
    on_done: Callable[[dict, object], None] | None = None,
    unit: str = "job",
) -> Ran:
    """Run (or resume) ``jobs`` of ``kind``, each result stored in ``store`` (an SQLite file;
    None: the jobs keep their own state and are run every time).

    ``backend`` ``local`` runs ``workers`` processes (this process for 1); ``ray`` runs Ray
    tasks of ``cpus_per_job`` CPUs, on the cluster at ``address`` or a local instance of
    ``workers * cpus_per_job`` CPUs. ``on_done(job, result)`` is called as each job finishes.
    The progress bar named ``desc`` counts ``unit``, after a line with the count and an estimate
    of the time (:mod:`~stsf_gym.experiments.jobs.estimate`).
    A job that raises (or whose worker dies) is run once more, then reported in
    :class:`~stsf_gym.experiments.jobs.cache.JobsFailed` after the others finished.
    """
    runner = make_runner(backend, workers, address, cpus_per_job, current_run())
    if store is not None:
        store = Path(store)
        jobs = [json.loads(json.dumps(job)) for job in jobs]  # as they are saved and read back
        forget_failures(jobs, store, kind.key)
    configs = {kind.key(job): kind.resolve(job) for job in jobs} if kind.resolve else {}
    results = run_cached(
        kind.run,
        jobs,
        store,
        kind.key,
        runner,
        desc,
        config=(lambda job: configs[kind.key(job)]) if kind.resolve else None,
        on_done=on_done,
        check=kind.check,
        unit=unit,
        workers=workers,
    )
    return Ran(results, configs)


def forget_failures(jobs: list[dict], store: Path, key: Callable[[dict], str]) -> None:
    """Delete the rows of ``jobs`` that failed (kept as results, :func:`~.spec.failure`), so
    that this run redoes them."""
    if not store.is_file():  # nothing stored yet: nothing made before the run's checks pass
        return
    keys = {key(job) for job in jobs}
    rows = read_rows(open_store(store))
    delete_rows(store, [k for k, row in rows.items() if k in keys and failed(row.result)])
