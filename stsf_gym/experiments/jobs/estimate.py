"""Time before work: what a run is about to do and how long it will take, said before it
starts, from a rate measured on this machine.

Every run of the job engine records its measured cost per job (wall seconds times the
processes running, over the jobs finished) under its description (``evaluate irl_corridor``,
``benchmark sparse``, ...) and its kind of work (:func:`work_key`) in a small JSON file in the
user's cache (:func:`rates_file`); the next run reads it back and prints its estimate: the jobs
still to do times that cost, over its processes. Jobs already done in the output folder are
counted as done. Work never run here falls back on the description's last rate, then on
:data:`REFERENCE_RATES` (measured on the project's 2-core machine), or says it has no rate.

Work of very unequal jobs (a training run: a few hundred decisions or a few million) keeps a
speed instead, units per second summed over every run of the work (:func:`record_speed`), and
estimates the units still to run over it (:func:`speed_estimate`); it never guesses.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import time
from pathlib import Path

from stsf_gym.io import write_json

RATES_ENV = "STSF_GYM_RATES"  # the rates file's path (default: <user cache>/stsf-gym/rates.json)
#: Seconds per job per process measured on the project's 2-core machine (2026-12-02, loaded
#: by training runs, load average 7-8: 24 demo episodes in 191 s on 2 processes).
REFERENCE_RATES = {"demo: episodes": 15.9}


def rates_file() -> Path:
    """Where measured rates are kept: ``$STSF_GYM_RATES``, else the user's cache folder."""
    if os.environ.get(RATES_ENV):
        return Path(os.environ[RATES_ENV])
    cache = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(cache) / "stsf-gym" / "rates.json"


def _rates() -> dict:
    try:
        rates = json.loads(rates_file().read_text())
    except (OSError, ValueError):
        return {}
    return rates if isinstance(rates, dict) else {}


def duration(seconds: float) -> str:
    """``seconds`` rounded as a person says it: 40 s, 3 min, 1.5 h."""
    if seconds < 90:
        return f"{max(1, round(seconds))} s"
    if seconds < 90 * 60:
        return f"{round(seconds / 60)} min"
    return f"{seconds / 3600:.1f} h"


def work_key(jobs: list[dict]) -> str:
    """What kind of work ``jobs`` are, apart from their seeds: a digest of their settings with
    ``seed`` and ``out`` (a run's own folder) left out (more seeds of the same work share it;
    another world or setting does not)."""
    own = ("seed", "out")
    kinds = sorted(
        {json.dumps({k: v for k, v in j.items() if k not in own}, default=str) for j in jobs}
    )
    return hashlib.sha1("\n".join(kinds).encode()).hexdigest()[:12]


def _measured(desc: str, key: str) -> tuple[float, str] | None:
    """The rate of ``desc`` on this work (else on other settings of it, else the reference)."""
    by_key = _rates().get(desc)
    by_key = by_key if isinstance(by_key, dict) else {}
    for found, where in ((by_key.get(key), "this work"), (by_key.get("last"), "other settings")):
        if isinstance(found, dict) and isinstance(found.get("seconds"), int | float):
            return float(found["seconds"]), f"measured here over {found.get('jobs')} on {where}"
    if desc in REFERENCE_RATES:
        return REFERENCE_RATES[desc], "measured on a loaded 2-core machine"
    return None


def plan_line(desc: str, unit: str, total: int, todo: list[dict], slots: int) -> str:
    """What the run will do (``todo`` of ``total`` jobs), and its estimate (see the module's
    docstring)."""
    if not todo:
        return f"{desc}: all {total} {unit}(s) already done"
    done = f" ({total - len(todo)} already done)" if len(todo) < total else ""
    head = f"{desc}: {len(todo)} {unit}(s) to run{done} on {slots} process(es)"
    measured = _measured(desc, work_key(todo))
    if measured is None:
        return f"{head}; no rate measured here yet: the bar's ETA follows the first {unit}s"
    rate, where = measured
    eta = len(todo) * rate / slots
    return f"{head}: about {duration(eta)} ({rate:.1f} s per {unit} per process, {where})"


class Stopwatch:
    """The measured cost of a run's ``jobs``: started before the first, :meth:`save` after the
    last finished (nothing recorded when none ran)."""

    def __init__(self, desc: str, jobs: list[dict], slots: int) -> None:
        self.desc, self.key, self.slots = desc, work_key(jobs), slots
        self.start, self.finished = time.monotonic(), 0

    def tick(self) -> None:
        """One more job finished."""
        self.finished += 1

    def save(self) -> None:
        """Record the seconds per job per process under the run's description and work (and
        as the description's ``last``)."""
        if not self.finished or not self.desc:
            return
        seconds = (time.monotonic() - self.start) * self.slots / self.finished
        record_rate(self.desc, self.key, seconds, self.finished)


def record_rate(desc: str, key: str, seconds: float, jobs: int) -> None:
    """Keep ``seconds`` per job per process, measured over ``jobs``, for ``desc``'s work
    ``key`` (:func:`work_key`) and as its ``last``."""
    rate = {"seconds": round(seconds, 2), "jobs": jobs}
    _keep(desc, {key: rate, "last": rate})


def record_speed(desc: str, key: str, units: float, seconds: float) -> None:
    """Add ``units`` run in ``seconds`` (one process) to ``desc``'s work ``key`` and to its
    ``any`` (every work of ``desc``): the speed is their sums' ratio, so a short run weighs
    little beside a long one."""
    if units <= 0 or seconds <= 0:
        return
    earlier = _rates().get(desc)
    kept: dict = earlier if isinstance(earlier, dict) else {}
    summed = {}
    for name in (key, "any"):
        old = kept.get(name)
        old = old if isinstance(old, dict) else {}
        summed[name] = {
            "units": _number(old.get("units")) + units,
            "seconds": round(_number(old.get("seconds")) + seconds, 2),
        }
    _keep(desc, summed)


def speed_estimate(desc: str, key: str, units: int, unit: str) -> tuple[float, str] | None:
    """The seconds ``units`` of ``desc``'s work ``key`` take on one process, with where the
    speed was measured (this work, else other work of ``desc``); None: never measured here."""
    kept = _rates().get(desc)
    kept = kept if isinstance(kept, dict) else {}
    for name, where in ((key, "this work"), ("any", "other settings")):
        found = kept.get(name)
        if isinstance(found, dict) and _number(found.get("units")) > 0:
            done, seconds = _number(found.get("units")), _number(found.get("seconds"))
            if seconds > 0:
                speed = done / seconds
                said = f"{speed:,.1f} {unit}s/s, measured here over {done:,.0f} on {where}"
                return units / speed, said
    return None


def _number(value: object) -> float:
    return float(value) if isinstance(value, int | float) else 0.0


def _keep(desc: str, entries: dict) -> None:
    """Write ``entries`` into ``desc``'s record in the rates file (what else it holds kept)."""
    rates = _rates()
    earlier = rates.get(desc)
    kept: dict = earlier if isinstance(earlier, dict) else {}
    rates[desc] = {**kept, **entries}
    try:
        rates_file().parent.mkdir(parents=True, exist_ok=True)
        write_json(rates_file(), rates)
    except OSError as err:  # a read-only home: the next run has no rate, nothing else
        print(f"{desc}: could not keep the measured rate ({err})", file=sys.stderr)


def slots_for(workers: int, todo: int) -> int:
    """Processes running at once: ``workers``, fewer when fewer jobs are left."""
    return max(1, min(workers, todo)) if todo else max(1, workers)
