"""The runs of a training folder (``stsf-gym train --seeds N``: ``seed-S/`` per seed), read
one way wherever a folder is named: ``benchmark``, ``accuracy-curve``, ``evaluate`` and
``agents --ship``.

A folder is taken whole or not at all: a ``seed-*`` entry that is not ``seed-<integer>/`` or a
seed whose run is unfinished (no ``model.zip`` yet) is refused by name, so no command scores or
ships the finished seeds alone without a word.
"""

from __future__ import annotations

import re
from pathlib import Path

from stsf_gym.validation import ConfigError

SEED_FOLDERS = "seed-*"  # the glob of a folder's runs
SEED_FOLDER = re.compile(r"seed-(0|[1-9][0-9]*)")  # seed-<integer>, as train names them
MODEL = "model.zip"
#: A fine-tuned run's clone: the policy its reward stage started from (and is pulled toward).
CLONE = "finetune/clone.zip"


def seed_runs(folder: str | Path) -> list[tuple[int, Path]]:
    """``(seed, run folder)`` of every ``seed-S/`` in ``folder``, by seed; empty for a folder
    of one run. A misnamed entry or an unfinished run raises :class:`ConfigError`."""
    folder = Path(folder)
    runs = []
    for path in sorted(folder.glob(SEED_FOLDERS)):
        match = SEED_FOLDER.fullmatch(path.name)
        if match is None or not path.is_dir():
            raise ConfigError(
                f"{path}: not a training seed's folder (seed-<integer>/, as `stsf-gym train "
                f"--seeds N` writes); move it out of {folder}"
            )
        if not (path / MODEL).is_file():
            raise ConfigError(
                f"{path}: an unfinished training run (no {MODEL}); finish it (rerun the same "
                f"`stsf-gym train` command) or move it out of {folder}: a folder's seeds are "
                "scored and shipped together"
            )
        runs.append((int(match.group(1)), path))
    return sorted(runs)


def folder_models(folder: str | Path) -> list[Path]:
    """The model of each run of training folder ``folder`` (``seed-S/model.zip``, or its own
    ``model.zip`` for one run); a folder with neither raises :class:`ConfigError`."""
    folder = Path(folder)
    models = [run / MODEL for _, run in seed_runs(folder)] or [folder / MODEL]
    if not models[0].is_file():
        raise ConfigError(
            f"agent folder {folder} holds no trained model: {models[0]} not found "
            "(a folder of `stsf-gym train --seeds N`, or of one run)"
        )
    return models
