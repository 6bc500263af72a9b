"""Checks of ``stsf-gym train`` made before any training starts or any file is written: the
seeds within what the learners' random generators take, and each run's ``--out`` free of the
trained work of another kind of run (another algorithm, pose source, world or suite), finished
or under way, which training there would overwrite.

A run of the same kind in ``--out`` is the run's own: a rerun resumes it, or finds it finished
and leaves it untouched (:mod:`stsf_gym.agents.training.train`). One finished by other code or
settings is trained afresh, its model and record first kept aside
(:mod:`stsf_gym.agents.training.replaced_runs`).
"""

from __future__ import annotations

import json
from pathlib import Path

from stsf_gym.agents.training.settings import resolve_run
from stsf_gym.envs.generated_env import generated_label
from stsf_gym.validation import ConfigError

#: numpy's legacy seeding (stable-baselines3's ``set_random_seed``) takes 0..2**32 - 1.
MAX_SEED = 2**32 - 1
#: What makes two training runs the same kind: a rerun of one into the other's folder resumes.
KIND_KEYS = ("algo", "estimator", "world", "suite")


def check_runs(runs: list[dict]) -> None:
    """Before any training: each of ``runs`` (the keyword arguments of
    :func:`~stsf_gym.agents.training.train.train`: ``algo``, ``estimator``, ``out``, ...) with
    every setting checked, and its folder free of another kind of run's trained work, the
    algorithm compared as the run will record it."""
    for run in runs:
        settings = resolve_run(
            run["algo"], run["estimator"], run["timesteps"], run["seed"], run["world"],
            run["config"], run["overrides"], run["n_envs"], run["suite"],
        )  # fmt: skip
        kind = run_kind(settings.algo, run["estimator"], run["world"], run["suite"])
        check_out(Path(run["out"]), kind)


def check_seeds(first: int, count: int) -> None:
    """Every training seed ``first .. first + count - 1`` within ``0 .. MAX_SEED``."""
    last = first + count - 1
    if first < 0 or last > MAX_SEED:
        raise ConfigError(
            f"--seed {first} --seeds {count}: training seeds must lie in 0..{MAX_SEED} "
            "(the learner seeds numpy's generator with each)"
        )


def run_kind(algo: str, estimator: str, world: str, suite: str | None) -> dict:
    """The :data:`KIND_KEYS` of a run of ``stsf-gym train`` with these options (a suite's runs
    train on its generated train worlds)."""
    world = generated_label("train") if suite is not None else world
    return {"algo": algo, "estimator": estimator, "world": world, "suite": suite}


def saved_kind(out: Path) -> tuple[dict, Path] | None:
    """The kind of run whose trained work lies in ``out`` and the file that says so: its
    ``train.json``, else its model's or a checkpoint's metadata; None for a folder without."""
    from stsf_gym.agents.model_files import model_metadata

    record = out / "train.json"
    if record.is_file():
        try:
            data = json.loads(record.read_text())
        except ValueError as err:
            raise ConfigError(f"{record} cannot be read as JSON ({err}): move it away") from None
        return {key: data.get(key) for key in KIND_KEYS}, record
    models = [out / "model.zip", *sorted((out / "checkpoints").glob("*_steps.zip"))]
    model = next((m for m in models if m.is_file()), None)
    if model is None:
        return None
    meta = model_metadata(model)
    return {key: meta.get(key) for key in KIND_KEYS}, model


def check_out(out: Path, kind: dict) -> None:
    """Refuse ``out`` when it holds the trained work of another kind of run than ``kind``."""
    saved = saved_kind(Path(out))
    if saved is None:
        return
    theirs, file = saved
    differ = [key for key in KIND_KEYS if theirs[key] != kind[key]]
    if differ:
        said = ", ".join(f"{key} {theirs[key]!r} (not {kind[key]!r})" for key in differ)
        raise ConfigError(
            f"{out} holds another training run ({file.name}: {said}); training here would "
            "overwrite it: choose another --out"
        )
