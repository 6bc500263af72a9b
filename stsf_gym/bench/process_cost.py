"""What a process costs before it does any work: import times and the first step.

Each figure comes from a fresh ``spawn`` process (nothing imported, nothing compiled in it yet;
the numba kernels' machine code already on disk, as in every process after a checkout's first),
best of ``rounds``, in seconds and in reference workloads (so machines of other speeds compare):

- ``import_env_s``: ``import stsf_gym`` (the env, its ids and wrappers), what every user pays;
- ``import_training_s``: the training stack on top (stable-baselines3, torch), what a worker
  that trains or drives a learnt agent pays;
- ``first_step_s``: ``gym.make`` of STSF on the fast camera, ``reset`` and one ``step``:
  PyBullet's world built, the compiled kernels loaded from their cache (numba's own start-up,
  about 3 s of it, is paid here, by the first kernel a process calls) and the first estimate.

Peak memory per env case is in the speed rows (:mod:`.speed`).
"""

from __future__ import annotations

import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np

FIRST_STEP_ID = "stsf_gym/Suite-Corridor-STSF-v0"


def _import_env() -> float:
    start = time.perf_counter()
    import stsf_gym  # noqa: F401 - the env's import is what is timed

    return time.perf_counter() - start


def _import_training() -> float:
    import stsf_gym  # paid apart, by _import_env

    start = time.perf_counter()
    import stsf_gym.agents.training.train  # noqa: F401 - the training stack's import is timed

    return time.perf_counter() - start


def _first_step() -> float:
    import gymnasium as gym

    import stsf_gym  # noqa: F401 - registers the ids; paid apart, by _import_env

    start = time.perf_counter()
    env = gym.make(FIRST_STEP_ID)
    env.reset(seed=0)
    env.step(np.zeros(env.action_space.shape, np.float32))
    seconds = time.perf_counter() - start
    env.close()
    return seconds


def _fresh(fn) -> float:
    """``fn()`` in a fresh spawned process."""
    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        return pool.submit(fn).result()


def process_costs(reference_ms: float, rounds: int = 3) -> dict[str, float]:
    """Each cost's best of ``rounds`` fresh processes, in seconds and in reference workloads
    (``*_references``: the cost over the reference workload's time)."""
    costs = {}
    for name, fn in (
        ("import_env_s", _import_env),
        ("import_training_s", _import_training),
        ("first_step_s", _first_step),
    ):
        seconds = min(_fresh(fn) for _ in range(rounds))
        costs[name] = seconds
        costs[name.removesuffix("_s") + "_references"] = 1e3 * seconds / reference_ms
    return costs
