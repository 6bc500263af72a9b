"""The machine's speed at the time of a run: a fixed reference workload, timed.

Speed figures (``stsf-gym bench``, a training run's steps per second) record it beside them,
so figures from runs on a busy or throttled machine can be told apart.
"""

from __future__ import annotations

import time

import numpy as np


def reference_ms() -> float:
    """Milliseconds of a fixed Python + numpy workload (best of 3): the machine's speed at the
    time of the run, so figures from runs on a busy or throttled machine can be told apart."""

    def work() -> None:
        sum(i * i for i in range(300_000))
        a = np.random.default_rng(0).standard_normal((200, 200))
        for _ in range(20):
            a = np.tanh(a @ a.T / 200)

    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        work()
        best = min(best, time.perf_counter() - start)
    return 1000 * best
