"""The job cache: each finished result a row of the run's store, so a rerun resumes.

A rerun skips every job whose row holds the same job, the same digest of its fully resolved
configuration and code that still computes what it did
(:class:`~stsf_gym.results.freshness.CurrentCode`), so an interrupted run resumes where it
stopped, while a result made by other code or settings (an edited default, a changed module)
is stale: it is recomputed, and the run says so. Rows are written in a transaction each
(:mod:`~stsf_gym.experiments.jobs.store`). A job whose worker raises or dies is reported on
stderr (name and error) and run once more; a job failing twice is reported in
:class:`JobsFailed` once every other job has finished and been stored. A job that meets a full
disk (``OSError`` ``ENOSPC``) stops the run at once with that error, the rows stored before
kept: the command line's one line for a full disk. Without a store
nothing is cached: the jobs keep their own state (a training run resumes from its checkpoint).
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, is_dataclass
from pathlib import Path

from tqdm import tqdm

from stsf_gym.experiments.jobs.estimate import Stopwatch, plan_line, slots_for
from stsf_gym.experiments.jobs.spec import Crash, Runner
from stsf_gym.experiments.jobs.store import Row, open_store, read_rows, write_row
from stsf_gym.io import to_builtin
from stsf_gym.results.fingerprint import config_digest
from stsf_gym.results.freshness import CurrentCode

ATTEMPTS = 2  # runs of a job before it is given up


class JobsFailed(RuntimeError):
    """Jobs that failed on every attempt; the finished ones are saved."""

    def __init__(self, failures: dict[str, str], store: Path | None) -> None:
        listed = "; ".join(f"{name}: {error}" for name, error in failures.items())
        kept = f"finished results are kept in {store} and " if store is not None else ""
        super().__init__(
            f"{len(failures)} job(s) failed {ATTEMPTS} times ({listed}); {kept}a rerun with "
            "the same output folder retries the rest"
        )
        self.failures = failures


@dataclass(frozen=True)
class Plan:
    """What a run of ``jobs`` against a store does: the keys of the jobs to run, and of those
    among them whose stored result was made by other code or settings."""

    todo: list[str]
    stale: list[str]


def plan(
    jobs: list[dict],
    rows: Mapping[str, Row],
    key: Callable[[dict], str],
    configs: Mapping[str, str],
    code: CurrentCode,
) -> Plan:
    """Which ``jobs`` a run redoes: those without a row in ``rows``, with a row of another job
    or config digest (``configs`` by key), or made by code that computes otherwise now."""
    todo, stale = [], []
    for job in jobs:
        row = rows.get(key(job))
        if row is not None and row.job == job:
            if row.config == configs[key(job)] and code.is_current(row.code):
                continue
            stale.append(key(job))
        todo.append(key(job))
    return Plan(todo, stale)


def run_cached(
    fn: Callable[[dict], object],
    jobs: list[dict],
    store: Path | None,
    name: Callable[[dict], str],
    runner: Runner,
    desc: str = "jobs",
    config: Callable[[dict], Mapping] | None = None,
    on_done: Callable[[dict, object], None] | None = None,
    check: Callable[[object, Mapping | None], str | None] | None = None,
    unit: str = "job",
    workers: int = 1,
) -> list:
    """``fn(job)`` for every job, its result (as a dict, when ``store`` keeps it), in job order.

    ``runner`` executes the jobs still to do; each result is stored in ``store`` (an SQLite
    file, when given) as soon as the runner yields it, then ``on_done(job, result)`` is called.
    The progress bar is named ``desc`` and counts ``unit`` (none when ``desc`` is empty: the
    caller shows progress in ``on_done``); before any job runs, the count to run and an
    estimate of their time on ``workers`` processes go to stderr
    (:mod:`~stsf_gym.experiments.jobs.estimate`). ``config(job)`` is the job's fully resolved
    configuration (every value, not only the job's overrides), whose digest a stored result
    must match to be reused. ``check(result, config)`` says what is wrong with a stored result
    (None: nothing); one that fails is recomputed.
    """
    configs = {name(job): config_digest(config(job) if config else {}) for job in jobs}
    code = CurrentCode()
    done: dict[str, object] = {}
    if store is not None:
        open_store(store)
        rows = read_rows(store)
        steps = plan(jobs, rows, name, configs, code)
        done = {k: row.result for k, row in rows.items() if k not in set(steps.todo)}
        inconsistent = []
        for job in jobs:
            key = name(job)
            problem = (
                check(done[key], config(job) if config else None) if check and key in done else None
            )
            if problem:
                inconsistent.append(f"{key}: {problem}")
                del done[key]
        if inconsistent:
            print(
                f"{desc}: {len(inconsistent)} saved result(s) in {store} fail their own check "
                f"(e.g. {inconsistent[0]}); recomputing them",
                file=sys.stderr,
            )
        if steps.stale:
            print(
                f"{desc}: {len(steps.stale)} stored result(s) in {store} were made by other code "
                f"or settings (e.g. {steps.stale[0]}); recomputing them",
                file=sys.stderr,
            )
    todo = [job for job in jobs if name(job) not in done]
    errors: dict[str, str] = {}
    slots = slots_for(workers, len(todo))
    if desc:
        print(plan_line(desc, unit, len(jobs), todo, slots), file=sys.stderr)
    bar = {"total": len(jobs), "initial": len(jobs) - len(todo), "desc": desc, "unit": unit}
    clock = Stopwatch(desc, todo, slots)
    with tqdm(**bar, disable=not desc) as progress:
        for attempt in range(1, ATTEMPTS + 1):
            failed = []
            for job, outcome in runner(fn, todo):
                if isinstance(outcome, Crash):
                    if outcome.full_disk is not None:  # no retry: every job would fail alike
                        raise outcome.full_disk  # the stored rows stay; a rerun resumes
                    failed.append(job)
                    errors[name(job)] = outcome.error
                    then = "running it again" if attempt < ATTEMPTS else "giving up"
                    what = f"{desc}: {name(job)}" if desc else name(job)
                    tqdm.write(f"{what} failed: {outcome.error}; {then}", sys.stderr)
                    continue
                result = outcome.result
                if store is not None:
                    if is_dataclass(result) and not isinstance(result, type):
                        result = asdict(result)
                    record = code.record(outcome.modules)
                    write_row(store, name(job), job, configs[name(job)], record, result)
                    result = json.loads(json.dumps(result, default=to_builtin))
                done[name(job)] = result
                clock.tick()
                progress.update()
                if on_done is not None:
                    on_done(job, outcome.result)
            todo = failed
            if not todo:
                break
    clock.save()
    if todo:
        raise JobsFailed({name(job): errors[name(job)] for job in todo}, store)
    return [done[name(job)] for job in jobs]
