"""Where jobs run: local processes (the default) or Ray tasks.

Both are runners (:data:`~stsf_gym.experiments.jobs.spec.Runner`): they yield each job's result
as it finishes (:class:`~stsf_gym.experiments.jobs.spec.Finished`), or a
:class:`~stsf_gym.experiments.jobs.spec.Crash` for a job that raised or whose worker died, and
:func:`~stsf_gym.experiments.jobs.cache.run_cached` stores it and moves the progress bar, so
the store, resume and summary are the same whichever backend ran them. Each job's worker
reports the package modules it had loaded (:func:`finished`): the code its stored result was
made with, and part of the provenance of the run the runner was made for (its
:class:`~stsf_gym.results.run_context.RunContext`, noted into as each job finishes).
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import get_context
from typing import Any

from stsf_gym.experiments.jobs.orphan_watchdog import start_watchdog
from stsf_gym.experiments.jobs.spec import Crash, Finished, Runner
from stsf_gym.results.code_identity import loaded_modules, run_reporting_modules, worker_result
from stsf_gym.results.run_context import RunContext, current_run
from stsf_gym.validation import ConfigError

BACKENDS = ("local", "ray")
RAY_CONNECT_TIMEOUT_S = 5.0  # a cluster's head answers a TCP connection in well under this
#: s: the most a Ray driver may take to join the cluster at ``--address`` (a few seconds on a
#: loaded machine); a service that is not Ray's keeps ``ray.init`` waiting for minutes
RAY_JOIN_TIMEOUT_S = 45.0
#: Joins the cluster at ``sys.argv[1]`` and leaves (run in a child process, killed if late).
RAY_PROBE = "import sys, ray; ray.init(address=sys.argv[1], log_to_driver=False); ray.shutdown()"
PARENT_CHECK_S = 2.0  # how often a local worker checks that the run that started it still runs


def make_runner(
    backend: str,
    workers: int = 2,
    address: str | None = None,
    cpus_per_job: int = 1,
    context: RunContext | None = None,
) -> Runner:
    """The runner of ``backend``: ``local`` processes or ``ray`` (``address`` or a local Ray;
    each job reserves ``cpus_per_job`` of its CPUs), its workers' modules noted as
    ``context``'s (the run current now if None)."""
    context = current_run() if context is None else context
    if workers < 1:
        raise ConfigError(f"workers must be at least 1, got {workers}")
    if backend == "local":
        if address is not None:
            raise ConfigError("--address is only for --backend ray")
        return process_runner(workers, context)
    if backend == "ray":
        check_ray_address(address)
        return ray_runner(address, workers, cpus_per_job, context)
    raise ConfigError(f"unknown backend {backend!r}; known: {', '.join(BACKENDS)}")


def check_ray_address(
    address: str | None,
    timeout_s: float = RAY_CONNECT_TIMEOUT_S,
    join_timeout_s: float = RAY_JOIN_TIMEOUT_S,
) -> None:
    """Fail before any work when no Ray cluster answers at ``address``: a host and port
    (``head:6379``, ``ray://head:10001``) where nothing answers within ``timeout_s`` (``ray.init``
    would retry there for minutes without a word), or where a driver cannot join within
    ``join_timeout_s`` (a service that is not Ray's), or ``auto`` with no cluster running.
    None and ``local`` (a local Ray, started by the run) are not checked."""
    if address in (None, "local"):
        return
    if address != "auto":
        _check_answers(address, timeout_s)
    try:
        joined = subprocess.run(
            [sys.executable, "-c", RAY_PROBE, address],
            capture_output=True,
            text=True,
            timeout=join_timeout_s,
        )
    except subprocess.TimeoutExpired:
        raise ConfigError(
            f"--address {address}: no Ray cluster let a driver join within {join_timeout_s:g} s "
            "(something answers there, but not Ray's GCS?); give the head's GCS port (6379) "
            "or ray://head:10001, or leave --address out for a local Ray"
        ) from None
    if joined.returncode:
        said = (joined.stderr.strip().splitlines() or ["no message"])[-1]
        raise ConfigError(f"--address {address}: no Ray cluster to join ({said[:300]})")


def _check_answers(address: str, timeout_s: float) -> None:
    """A host and port where something answers a TCP connection within ``timeout_s``."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not (sep and host and port.isdigit()):
        raise ConfigError(f"--address {address!r}: give host:port or ray://host:port (or auto)")
    try:
        socket.create_connection((host, int(port)), timeout=timeout_s).close()
    except OSError as err:
        raise ConfigError(
            f"--address {address}: nothing answers there ({err.strerror or err}); start the "
            "cluster (`ray start --head`) or leave --address out for a local Ray"
        ) from None


def ray_runner(
    address: str | None = None,
    workers: int = 2,
    cpus_per_job: int = 1,
    context: RunContext | None = None,
) -> Runner:
    """Jobs as Ray tasks (``cpus_per_job`` CPUs each), gathered with ``ray.wait`` as they
    finish, their modules noted as ``context``'s (the run current now if None).

    Uses the Ray instance already initialised in this process, else connects to ``address``
    (a running cluster, e.g. ``ray://head:10001`` or ``auto``) or, without one, starts a local
    instance of ``workers * cpus_per_job`` CPUs (``workers`` jobs at once); an instance it
    started is shut down when the jobs are done, or by a watchdog when the run is killed
    (:mod:`~stsf_gym.experiments.jobs.orphan_watchdog`).
    Nodes of a cluster need stsf-gym installed.
    """
    context = current_run() if context is None else context
    try:
        import ray
    except ImportError as err:
        raise ConfigError(
            "the ray backend needs Ray: pip install 'stsf-gym[ray]' (or pip install ray)"
        ) from err

    def run(
        fn: Callable[[dict], object], jobs: list[dict]
    ) -> Iterator[tuple[dict, Finished | Crash]]:
        if not jobs:
            return
        started = not ray.is_initialized()
        watchdog = None
        if started:
            local: dict[str, Any] = {} if address else {"num_cpus": workers * cpus_per_job}
            ray.init(address=address, include_dashboard=False, log_to_driver=False, **local)
            watchdog = None if address else start_watchdog()  # a kill leaves no Ray agents
        task = ray.remote(num_cpus=cpus_per_job, max_retries=0)(run_reporting_modules)
        task = task.options(name=getattr(fn, "__name__", "job"))  # errors name the job's function
        pending = {task.remote(fn, job): job for job in jobs}
        try:
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1)
                job = pending.pop(done[0])
                try:
                    result: Finished | Crash = finished(ray.get(done[0]), context)
                except ray.exceptions.RayError as err:  # the job raised, its worker died...
                    result = Crash.of(err)
                yield job, result
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)
            if started:
                ray.shutdown()
            if watchdog is not None:
                watchdog.terminate()

    return run


def process_runner(workers: int, context: RunContext | None = None) -> Runner:
    """Jobs in ``workers`` forkserver processes (in this process when ``workers`` is 1), their
    modules noted as ``context``'s (the run current now if None).

    Each of the ``workers`` slots owns a one-process pool, so a worker that dies takes down
    only the job it was running: that job is yielded as a :class:`Crash`, and the slot starts
    a fresh process for its next job. An exception raised by ``fn`` is a :class:`Crash` too;
    in this process (``workers`` 1) only exceptions are caught, a dying job ends the run.
    A worker whose run was killed exits within :data:`PARENT_CHECK_S` (:func:`exit_with`):
    its job's result was lost with the run, and a rerun redoes it.
    """
    context = current_run() if context is None else context

    def run(
        fn: Callable[[dict], object], jobs: list[dict]
    ) -> Iterator[tuple[dict, Finished | Crash]]:
        if not jobs:
            return
        if workers <= 1:
            for job in jobs:
                try:
                    result = fn(job)
                except Exception as err:
                    yield job, Crash.of(err)
                else:
                    yield job, Finished(result, loaded_modules())
            return
        slot, pools, lock = threading.local(), [], threading.Lock()

        def in_own_process(job: dict) -> tuple[object, list[str]]:
            if getattr(slot, "pool", None) is None:
                slot.pool = ProcessPoolExecutor(
                    1,
                    mp_context=get_context("forkserver"),
                    initializer=exit_with,
                    initargs=(os.getpid(),),
                )
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
                    error = future.exception()
                    yield (
                        futures[future],
                        Crash.of(error) if error else finished(future.result(), context),
                    )
            finally:
                for future in futures:
                    future.cancel()
                with lock:
                    for pool in pools:
                        pool.shutdown(cancel_futures=True)

    return run


def finished(reply: tuple[object, list[str]], context: RunContext) -> Finished:
    """A worker's :func:`~stsf_gym.results.code_identity.run_reporting_modules` reply as a
    :class:`Finished`, its modules noted as ``context``'s."""
    return Finished(worker_result(reply, context), reply[1])


def exit_with(run_pid: int) -> None:
    """In a worker: exit as soon as process ``run_pid`` (the run that started it) is gone.

    A forkserver worker is the forkserver's child, not the run's, so it outlives a run killed
    alone (``kill PID``, not its process group) and would hold its memory idle; a daemon thread
    checks every :data:`PARENT_CHECK_S` seconds instead."""

    def watch() -> None:
        while True:
            time.sleep(PARENT_CHECK_S)
            try:
                os.kill(run_pid, 0)
            except OSError:  # gone (or its pid reused by another user's process)
                os._exit(1)

    threading.Thread(target=watch, name="exit-with-run", daemon=True).start()
