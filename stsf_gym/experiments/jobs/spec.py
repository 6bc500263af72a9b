"""What the job engine runs: a kind of job, what a finished job hands back, what a failed one
leaves behind.

A job is a JSON-friendly dict. Its :class:`JobKind` says how to run one (in a worker process
or a Ray task, so it must be a module-level function), its key (unique within a run) and its
resolved configuration (every value it runs with: what a stored result must match, with the
code it ran with, :mod:`stsf_gym.results.freshness`).
"""

from __future__ import annotations

import errno
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass


@dataclass(frozen=True)
class JobKind:
    """A kind of job: how to ``run`` one, its ``key``, ``resolve``: its resolved
    configuration (None: a result that depends on nothing but the job and the code), and
    ``check``: what is wrong with a saved result given that configuration (None: nothing;
    :mod:`~stsf_gym.experiments.jobs.checks`), so a result edited by hand is recomputed."""

    run: Callable[[dict], object]
    key: Callable[[dict], str]
    resolve: Callable[[dict], Mapping] | None = None
    check: Callable[[object, Mapping | None], str | None] | None = None


@dataclass(frozen=True)
class Finished:
    """What a runner yields for a job that returned: its result and the package modules its
    process had loaded (relative paths), the code the result was made with."""

    result: object
    modules: list[str]


@dataclass(frozen=True)
class Crash:
    """What a runner yields for a job whose worker raised or died: the error, in words, and
    the ``OSError`` ``ENOSPC`` when it met a full disk (every job after it would too: the run
    stops on it, :func:`~stsf_gym.experiments.jobs.cache.run_cached`)."""

    error: str
    full_disk: OSError | None = None

    @classmethod
    def of(cls, err: BaseException) -> Crash:
        """The crash an exception of a job stands for (a dead worker process is named as such)."""
        if isinstance(err, BrokenProcessPool):
            return cls("the worker process died (killed, os._exit or a crash in native code)")
        first_line = (str(err).strip().splitlines() or [""])[0]
        return cls(f"{type(err).__name__}: {first_line}", full_disk_error(err))


def full_disk_error(err: BaseException) -> OSError | None:
    """The ``OSError`` ``ENOSPC`` that ``err`` is, or wraps as a Ray task's error does (its
    ``cause``); None for any other error."""
    for candidate in (err, getattr(err, "cause", None)):
        if isinstance(candidate, OSError) and candidate.errno == errno.ENOSPC:
            return candidate
    return None


#: Runs ``fn`` on each job, yielding ``(job, Finished or Crash)`` in the order they finish.
Runner = Callable[[Callable[[dict], object], list[dict]], Iterable[tuple[dict, Finished | Crash]]]


def failure(err: BaseException, details: str = "") -> dict:
    """The result a job that keeps its failures as results (a sweep cell) records for ``err``:
    the first line of its message, and the traceback (or the whole message)."""
    message = (str(err).strip().splitlines() or [""])[0]
    return {"error": f"{type(err).__name__}: {message}", "traceback": details or str(err)}


def failed(result: object) -> bool:
    """Whether ``result`` is a failure kept as a result (:func:`failure`)."""
    return isinstance(result, dict) and "error" in result
