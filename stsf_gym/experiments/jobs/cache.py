"""The job cache: each finished result in its own JSON file, so a rerun resumes.

A rerun skips every job whose file holds the same job and the same
:func:`~stsf_gym.results.provenance.fingerprint` (the code's digest and the job's fully resolved
configuration), so an interrupted run resumes where it stopped, while a result made by other
code or settings (an edited default, a changed module) is stale: it is recomputed, and the run
says so. Files are written atomically, and a file that cannot be read back counts as not done.
A job whose worker raises or dies is reported on stderr (name and error) and run once more; a
job failing twice is reported in :class:`JobsFailed` once every other job has finished and been
saved. Without a folder nothing is cached: the jobs keep their own state (a training run
resumes from its checkpoint).
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Mapping
from dataclasses import asdict, is_dataclass
from pathlib import Path

from tqdm import tqdm

from stsf_gym.experiments.jobs.estimate import Stopwatch, plan_line, slots_for
from stsf_gym.experiments.jobs.spec import Crash, Runner
from stsf_gym.io import write_json
from stsf_gym.results.provenance import fingerprint

ATTEMPTS = 2  # runs of a job before it is given up


class JobsFailed(RuntimeError):
    """Jobs that failed on every attempt; the finished ones are saved."""

    def __init__(self, failures: dict[str, str], folder: Path | None) -> None:
        listed = "; ".join(f"{name}: {error}" for name, error in failures.items())
        kept = f"finished results are kept in {folder} and " if folder is not None else ""
        super().__init__(
            f"{len(failures)} job(s) failed {ATTEMPTS} times ({listed}); {kept}a rerun with "
            "the same output folder retries the rest"
        )
        self.failures = failures


def run_cached(
    fn: Callable[[dict], object],
    jobs: list[dict],
    folder: Path | None,
    name: Callable[[dict], str],
    runner: Runner,
    desc: str = "jobs",
    config: Callable[[dict], Mapping] | None = None,
    on_done: Callable[[dict, object], None] | None = None,
    check: Callable[[object, Mapping | None], str | None] | None = None,
    unit: str = "job",
    workers: int = 1,
) -> list:
    """``fn(job)`` for every job, its result (as a dict, when ``folder`` keeps it), in job order.

    ``runner`` executes the jobs still to do; each result is saved in ``folder`` (when given)
    as soon as the runner yields it, then ``on_done(job, result)`` is called. The progress bar
    is named ``desc`` and counts ``unit`` (none when ``desc`` is empty: the caller shows progress
    in ``on_done``); before any job runs, the count to run and an estimate of their time on
    ``workers`` processes go to stderr (:mod:`~stsf_gym.experiments.jobs.estimate`). ``config(job)``
    is the job's fully resolved configuration (every value, not only the job's overrides): part
    of the fingerprint a saved result must match to be reused. ``check(result, config)``
    says what is wrong with a saved result (None: nothing); one that fails is recomputed.
    """
    made_by = {name(job): fingerprint(config(job) if config else None) for job in jobs}
    done: dict[str, object] = {}
    stale, inconsistent = [], []

    def load(job: dict, note_stale: bool = False) -> object | None:
        if folder is None:
            return done.get(name(job))
        try:
            data = json.loads((folder / f"{name(job)}.json").read_text())
        except (OSError, ValueError):  # not there yet, or not readable: run the job again
            return None
        if not isinstance(data, dict) or data.get("job") != job:
            return None
        if data.get("made_by") != made_by[name(job)]:
            if note_stale:
                stale.append(name(job))
            return None
        problem = check(data["result"], config(job) if config else None) if check else None
        if problem:
            if note_stale:
                inconsistent.append(f"{name(job)}: {problem}")
            return None
        return data["result"]

    def save(job: dict, result: object) -> None:
        if folder is None:
            done[name(job)] = result
            return
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
    if inconsistent:
        print(
            f"{desc}: {len(inconsistent)} saved result(s) in {folder} fail their own check "
            f"(e.g. {inconsistent[0]}); recomputing them",
            file=sys.stderr,
        )
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
                    failed.append(job)
                    errors[name(job)] = outcome.error
                    then = "running it again" if attempt < ATTEMPTS else "giving up"
                    what = f"{desc}: {name(job)}" if desc else name(job)
                    tqdm.write(f"{what} failed: {outcome.error}; {then}", sys.stderr)
                    continue
                save(job, outcome)
                clock.tick()
                progress.update()
                if on_done is not None:
                    on_done(job, outcome)
            todo = failed
            if not todo:
                break
    clock.save()
    if todo:
        raise JobsFailed({name(job): errors[name(job)] for job in todo}, folder)
    return [load(job) for job in jobs]
