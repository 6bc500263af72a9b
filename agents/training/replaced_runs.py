"""A finished training run is never overwritten: one made by other code or settings than a new
run in the same folder is moved aside before that run starts afresh.

``stsf-gym train`` reruns into its ``--out``: the same run is resumed or left untouched, another
kind of run is refused (:mod:`stsf_gym.agents.training.preflight`), and the same kind made by
other code or settings (a default edited, the package updated) is trained again. Its
checkpoints go to ``stale-checkpoints/``; :func:`keep_replaced_run` keeps its ``model.zip`` and
``train.json`` in ``replaced-runs/<n>/``, which the default learner (no RL checkpoints) would
otherwise lose.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def keep_replaced_run(out: Path, made_by: dict) -> Path | None:
    """Before a run starts afresh in ``out`` over a run finished there by other code or
    settings (its ``train.json`` has another ``made_by``): move that run's ``model.zip`` and
    ``train.json`` to ``replaced-runs/<n>/``, say so on stderr and return the folder; None when
    there is nothing to keep (no finished run, or this run's own, resumed or extended)."""
    record, model = out / "train.json", out / "model.zip"
    if not (record.is_file() and model.is_file()):
        return None
    if json.loads(record.read_text()).get("made_by") == made_by:
        return None
    kept = out / "replaced-runs"
    kept.mkdir(exist_ok=True)
    folder = kept / str(len(list(kept.iterdir())))
    folder.mkdir()
    for file in (model, record):  # the model first: a train.json alone marks no finished run
        file.rename(folder / file.name)
    print(
        f"{out}: the run finished there was made by other code or settings; its model.zip and "
        f"train.json are kept in {folder} and training starts afresh",
        file=sys.stderr,
    )
    return folder
