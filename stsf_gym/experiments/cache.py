"""Run many jobs (in processes), keeping each finished result in its own JSON file.

A rerun skips every job whose file holds the same job description, so an interrupted run
resumes where it stopped and a changed config recomputes; files are written atomically.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, is_dataclass
from multiprocessing import get_context
from pathlib import Path

from tqdm import tqdm

from stsf_gym.io import write_json


def run_cached(
    fn: Callable[[dict], object],
    jobs: list[dict],
    folder: str | Path,
    name: Callable[[dict], str],
    workers: int = 1,
    desc: str = "jobs",
) -> list[dict]:
    """``fn(job)`` for every job (a JSON-friendly dict), its result as a dict, in job order."""
    folder = Path(folder)
    jobs = [json.loads(json.dumps(job)) for job in jobs]

    def load(job: dict) -> dict | None:
        path = folder / f"{name(job)}.json"
        if not path.is_file():
            return None
        data = json.loads(path.read_text())
        return data["result"] if data.get("job") == job else None

    def save(job: dict, result: object) -> None:
        result = asdict(result) if is_dataclass(result) else result
        write_json(folder / f"{name(job)}.json", {"job": job, "result": result})

    todo = [job for job in jobs if load(job) is None]
    with tqdm(total=len(jobs), initial=len(jobs) - len(todo), desc=desc) as progress:
        if workers > 1 and len(todo) > 1:
            with ProcessPoolExecutor(workers, mp_context=get_context("forkserver")) as pool:
                for job, result in zip(todo, pool.map(fn, todo), strict=True):
                    save(job, result)
                    progress.update()
        else:
            for job in todo:
                save(job, fn(job))
                progress.update()
    return [load(job) for job in jobs]
