"""RLlib entry point: ``register_env("stsf_gym", env_creator)`` (in ``agents``, as the policy
observation is the SB3 agents').

```python
from ray.rllib.algorithms.ppo import PPOConfig
from ray.tune.registry import register_env
from stsf_gym.agents.rllib import env_creator

register_env("stsf_gym", env_creator)
config = PPOConfig().environment(
    "stsf_gym", env_config={"env_id": "stsf_gym/Corridor-STSF-v0", "camera__mode": "fast"}
)
```

``env_config`` keys: ``env_id`` (a registered id, default :data:`DEFAULT_ID`), ``seed`` (the
base seed, default 0), ``policy_observation`` (default true: the flat ``Box`` of
:class:`stsf_gym.agents.observation.PolicyObservation` that the SB3 agents use, for MLP policies;
needs an estimating id; false keeps the ``Dict`` observation); every other key goes to
``gymnasium.make`` (``camera__mode="fast"``, ``sim__max_episode_seconds=60``, ...).

Each env is reset once here with its own seed, drawn from the base seed, the env runner's
``worker_index``, the ``vector_index`` and how many envs this process made before for that
pair (RLlib's new API stack builds every sub-env of a runner from the same context), so no two
envs share a random stream and a rerun repeats them all. ``config.debugging(seed=...)`` makes
RLlib seed the first reset itself instead. Needs ``pip install 'stsf-gym[rllib]'`` (Ray's
RLlib pins its own Gymnasium release).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping

import gymnasium as gym
import numpy as np

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.agents.observation import PolicyObservation

DEFAULT_ID = "stsf_gym/Corridor-Truth-v0"
_made: Counter = Counter()  # envs this process made per (worker_index, vector_index)


def env_seed(base: int, worker_index: int, vector_index: int, nth: int) -> int:
    """A seed of its own for the ``nth`` env made for one (worker, vector) slot."""
    sequence = np.random.SeedSequence([base, worker_index, vector_index, nth])
    return int(sequence.generate_state(1)[0])


def env_creator(config: Mapping) -> gym.Env:
    """An stsf-gym env for RLlib from an ``EnvContext`` (or a plain mapping: worker 0)."""
    settings = dict(config)
    settings.pop("num_envs", None)  # RLlib's vector entry point adds it
    env_id = settings.pop("env_id", DEFAULT_ID)
    base = int(settings.pop("seed", 0))
    flat = bool(settings.pop("policy_observation", True))
    slot = (getattr(config, "worker_index", 0), getattr(config, "vector_index", 0))
    seed = env_seed(base, *slot, _made[slot])
    _made[slot] += 1
    env = gym.make(env_id, **settings)
    if flat:
        try:
            env = PolicyObservation(env)
        except ValueError:
            env.close()
            raise
    env.reset(seed=seed)
    return env
