"""Run many jobs (in processes), keeping each finished result in its own JSON file.

A rerun skips every job whose file holds the same job description and the same
:func:`~stsf_gym.results.provenance.fingerprint` (the code's digest and the job's fully resolved
configuration), so an interrupted run resumes where it stopped, while a result made by other
code or settings (an edited default, a changed module) is stale: it is recomputed, and the run
says so. Files are written atomically, and a file that cannot be read back counts as not done.
A job whose worker raises or dies is reported on stderr (name and error) and run once more; a
job failing twice is reported in :class:`JobsFailed` once every other job has finished and been
saved. A job run in a worker process reports the package modules the worker loaded, so the run's
provenance lists them (:func:`~stsf_gym.results.provenance.loaded_code`); its result is
unchanged.
"""

from __future__ import annotations

import json
import sys
import threading
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import asdict, dataclass, is_dataclass
from multiprocessing import get_context
from pathlib import Path

from tqdm import tqdm

from stsf_gym.io import write_json
from stsf_gym.results.provenance import fingerprint, run_reporting_modules, worker_result

ATTEMPTS = 2  # runs of a job before it is given up


@dataclass(frozen=True)
class Crash:
    """What a runner yields for a job whose worker raised or died: the error, in words."""

    error: str

    @classmethod
    def of(cls, err: BaseException) -> Crash:
        """The crash an exception of a job stands for (a dead worker process is named as such)."""
        if isinstance(err, BrokenProcessPool):
            return cls("the worker process died (killed, os._exit or a crash in native code)")
        first_line = (str(err).strip().splitlines() or [""])[0]
        return cls(f"{type(err).__name__}: {first_line}")


class JobsFailed(RuntimeError):
    """Jobs that failed on every attempt; the finished ones are saved."""

    def __init__(self, failures: dict[str, str], folder: Path, attempts: int = ATTEMPTS) -> None:
        listed = "; ".join(f"{name}: {error}" for name, error in failures.items())
        times = "once" if attempts == 1 else f"{attempts} times"
        super().__init__(
            f"{len(failures)} job(s) failed {times} ({listed}); finished results are "
            f"kept in {folder} and a rerun with the same output folder retries the rest"
        )
        self.failures = failures


#: Runs ``fn`` on each job, yielding ``(job, result or Crash)`` in the order they finish.
Runner = Callable[[Callable[[dict], object], list[dict]], Iterable[tuple[dict, object]]]


def run_cached(
    fn: Callable[[dict], object],
    jobs: list[dict],
    folder: str | Path,
    name: Callable[[dict], str],
    workers: int = 1,
    desc: str = "jobs",
    runner: Runner | None = None,
    config: Callable[[dict], Mapping] | None = None,
) -> list[dict]:
    """``fn(job)`` for every job (a JSON-friendly dict), its result as a dict, in job order.

    ``runner`` executes the jobs still to do (default: :func:`process_runner` of ``workers``);
    each result is saved as soon as the runner yields it. ``config(job)`` is the job's fully
    resolved configuration (every value, not only the job's overrides): part of the
    fingerprint a saved result must match to be reused.
    """
    folder = Path(folder)
    jobs = [json.loads(json.dumps(job)) for job in jobs]
    made_by = {name(job): fingerprint(config(job) if config else None) for job in jobs}
    stale = []

    def load(job: dict, note_stale: bool = False) -> dict | None:
        path = folder / f"{name(job)}.json"
        try:
            data = json.loads(path.read_text())
        except (OSError, ValueError):  # not there yet, or not readable: run the job again
            return None
        if not isinstance(data, dict) or data.get("job") != job:
            return None
        if data.get("made_by") != made_by[name(job)]:
            if note_stale:
                stale.append(name(job))
            return None
        return data["result"]

    def save(job: dict, result: object) -> None:
        result = asdict(result) if is_dataclass(result) else result
        record = {"job": job, "made_by": made_by[name(job)], "result": result}
        write_json(folder / f"{name(job)}.json", record)

    todo = [job for job in jobs if load(job, note_stale=True) is None]
    if stale:
        print(
            f"{desc}: {len(stale)} saved result(s) in {folder} were made by other code or "
            f"settings (e.g. {stale[0]}); recomputing them",
            file=sys.stderr,
        )
    run = runner or process_runner(workers)
    errors: dict[str, str] = {}
    with tqdm(total=len(jobs), initial=len(jobs) - len(todo), desc=desc) as progress:
        for attempt in range(1, ATTEMPTS + 1):
            failed = []
            for job, outcome in run(fn, todo):
                if isinstance(outcome, Crash):
                    failed.append(job)
                    errors[name(job)] = outcome.error
                    then = "running it again" if attempt < ATTEMPTS else "giving up"
                    tqdm.write(f"{desc}: {name(job)} failed: {outcome.error}; {then}", sys.stderr)
                else:
                    save(job, outcome)
                    progress.update()
            todo = failed
            if not todo:
                break
    if todo:
        raise JobsFailed({name(job): errors[name(job)] for job in todo}, folder)
    return [load(job) for job in jobs]


def process_runner(workers: int) -> Runner:
    """Jobs in ``workers`` forkserver processes (in this process when ``workers`` is 1).

    Each of the ``workers`` slots owns a one-process pool, so a worker that dies takes down
    only the job it was running: that job is yielded as a :class:`Crash`, and the slot starts
    a fresh process for its next job. An exception raised by ``fn`` is a :class:`Crash` too;
    in this process (``workers`` 1) only exceptions are caught, a dying job ends the run.
    """

    def run(fn: Callable[[dict], object], jobs: list[dict]) -> Iterable[tuple[dict, object]]:
        if not jobs:
            return
        if workers <= 1:
            for job in jobs:
                try:
                    yield job, fn(job)
                except Exception as err:
                    yield job, Crash.of(err)
            return
        slot, pools, lock = threading.local(), [], threading.Lock()

        def in_own_process(job: dict) -> object:
            if getattr(slot, "pool", None) is None:
                slot.pool = ProcessPoolExecutor(1, mp_context=get_context("forkserver"))
                with lock:
                    pools.append(slot.pool)
            try:
                return slot.pool.submit(run_reporting_modules, fn, job).result()
            except BrokenProcessPool:
                slot.pool = None  # this slot's next job gets a fresh process
                raise

        with ThreadPoolExecutor(min(workers, len(jobs))) as threads:
            futures = {threads.submit(in_own_process, job): job for job in jobs}
            try:
                for future in as_completed(futures):
                    err = future.exception()
                    yield futures[future], Crash.of(err) if err else worker_result(future.result())
            finally:
                for future in futures:
                    future.cancel()
                with lock:
                    for pool in pools:
                        pool.shutdown(cancel_futures=True)

    return run
