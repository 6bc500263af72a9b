"""The stops in a step's ``info``, of one shape and type through an episode.

A recorder (Minari's ``DataCollector(record_infos=True)``, an HDF5 or Arrow column per key)
stores an ``info`` key only when its shape and type stay the same from reset to the last step;
a list of the stops so far grows. So ``info`` holds ``stops``, the count of stops declared, and
``last_stop``, the latest one as fixed fields (before the first: ``goal``, ``time`` and
``true_distance_m`` -1, as ``image_time`` before a frame; no NaN, which equals nothing, so a
checker comparing two runs' infos finds them equal). A stop either reaches its goal (the next
goal follows) or ends the episode, so the ``last_stop`` values over an episode hold every stop;
the whole list is ``env.unwrapped.task.stops``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from stsf_gym.envs.task import Stop

#: ``last_stop`` before any stop.
NO_STOP = {"goal": -1, "time": -1.0, "position": np.zeros(2), "true_distance_m": -1.0,
           "success": False}  # fmt: skip


def stop_info(stops: Sequence[Stop]) -> dict:
    """``last_stop`` of ``info``: the latest of ``stops`` as ``{goal, time, position (2,),
    true_distance_m, success}``, or :data:`NO_STOP` if none."""
    if not stops:
        return {**NO_STOP, "position": np.array(NO_STOP["position"], copy=True)}
    stop = stops[-1]
    return {
        "goal": int(stop.goal),
        "time": float(stop.time),
        "position": np.array(stop.position, dtype=np.float64),
        "true_distance_m": float(stop.true_distance_m),
        "success": bool(stop.success),
    }
