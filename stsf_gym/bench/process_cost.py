"""What a process costs before it does any work: import times and the first step.

Each figure comes from a fresh interpreter (nothing imported, nothing compiled in it yet;
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

import subprocess
import sys

FIRST_STEP_ID = "stsf_gym/Suite-Corridor-STSF-v0"
#: Each cost as a script for a fresh interpreter, printing the seconds it measured.
SCRIPTS = {
    "import_env_s": """
import time
start = time.perf_counter()
import stsf_gym
print(time.perf_counter() - start)
""",
    "import_training_s": """
import time
import stsf_gym
start = time.perf_counter()
import stsf_gym.agents.training.train
print(time.perf_counter() - start)
""",
    "first_step_s": f"""
import time
import gymnasium as gym
import numpy as np
import stsf_gym
start = time.perf_counter()
env = gym.make("{FIRST_STEP_ID}")
env.reset(seed=0)
env.step(np.zeros(env.action_space.shape, np.float32))
print(time.perf_counter() - start)
env.close()
""",
}


def _fresh(script: str) -> float:
    """The seconds ``script`` prints, run by a fresh interpreter (a process imports nothing of
    its parent's, as a spawned worker would its parent's main module)."""
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    )
    return float(done.stdout.split()[-1])


def process_costs(reference_ms: float, rounds: int = 3) -> dict[str, float]:
    """Each cost's best of ``rounds`` fresh processes, in seconds and in reference workloads
    (``*_references``: the cost over the reference workload's time)."""
    costs = {}
    for name, script in SCRIPTS.items():
        seconds = min(_fresh(script) for _ in range(rounds))
        costs[name] = seconds
        costs[name.removesuffix("_s") + "_references"] = 1e3 * seconds / reference_ms
    return costs
