"""``stsf-gym agents --ship``: a training folder shipped whole, checked, and swapped in at once.

It ships into the folder the user names (``--ship-to DIR``), never into the installed package
(:func:`check_ship_to`). Every check runs before anything in that folder changes: each
``seed-S/`` finished (:func:`~stsf_gym.agents.training_folder.seed_runs`), each model readable
to its weights, and each model's own metadata (algorithm, pose source, suite, seed, the
fingerprint of its settings) agreeing with its ``train.json``, with the other seeds and with
``--suite``. The agent is then
built in a temporary folder beside its destination and renamed into place; an agent already
shipped under that name is replaced only when asked (``replace``), and then as a whole (the old
folder renamed aside, the new one renamed in, the old one removed): a failure at any point
leaves the shipped agent as it was, never half replaced, and no seed of the old agent behind.
"""

from __future__ import annotations

import importlib.util
import io
import json
import os
import secrets
import shutil
import zipfile
from pathlib import Path

import torch

from stsf_gym.agents.model_files import trained_algo
from stsf_gym.agents.training_folder import MODEL, seed_runs
from stsf_gym.io import check_folder, write_json
from stsf_gym.results.code_identity import CODE_PACKAGES, git_state
from stsf_gym.validation import ConfigError

#: What a model's ``stsf_meta`` and its run's ``train.json`` must both say, and alike.
AGREED_KEYS = ("algo", "estimator", "suite", "seed", "made_by")
#: The optimizer's state in an SB3 model file.
OPTIMIZER = "policy.optimizer.pth"
#: What every seed of one shipped agent shares.
SHARED_KEYS = ("algo", "estimator", "suite")


def checked_runs(training: Path, suite: str) -> list[dict]:
    """The ``train.json`` record of each seed of ``training``, checked against its model and
    ``suite`` (:data:`AGREED_KEYS`, :data:`SHARED_KEYS`); ConfigError naming the first
    disagreement."""
    from stsf_gym.agents.model_files import check_weights, model_metadata

    runs = seed_runs(training)
    if not runs:
        raise ConfigError(f"{training}: no seed-S/{MODEL} to ship (a `train --seeds N` folder)")
    records = []
    for seed, run in runs:
        record = _train_record(run / "train.json")
        meta = model_metadata(check_weights(run / MODEL))
        for key in AGREED_KEYS:
            if record.get(key) != meta.get(key):
                raise ConfigError(
                    f"{run}: train.json says {key} {record.get(key)!r}, its model "
                    f"{meta.get(key)!r}; a shipped agent is what its models are"
                )
        if meta["seed"] != seed:
            raise ConfigError(f"{run}: its model was trained with seed {meta['seed']}, not {seed}")
        if meta["suite"] != suite:
            raise ConfigError(
                f"{run}: trained on suite {meta['suite']!r}, not --suite {suite!r}"
                if meta["suite"]
                else f"{run}: trained on world {meta['world']!r}, not on suite {suite!r}"
            )
        records.append(record)
    first = records[0]
    for record in records[1:]:
        for key in SHARED_KEYS:
            if record[key] != first[key]:
                raise ConfigError(
                    f"{training}: seed {record['seed']} has {key} {record[key]!r}, seed "
                    f"{first['seed']} {first[key]!r}; one shipped agent is one kind of run"
                )
    return records


def _train_record(path: Path) -> dict:
    """A run's ``train.json``, readable."""
    try:
        record = json.loads(path.read_text())
    except FileNotFoundError:
        raise ConfigError(f"{path} not found: the run is unfinished or not from `train`") from None
    except (OSError, ValueError) as err:
        raise ConfigError(f"{path} cannot be read as JSON: {err}") from None
    if not isinstance(record, dict):
        raise ConfigError(f"{path} holds no train.json record (a mapping)")
    return record


def package_folders() -> list[Path]:
    """The folders the package's code is read from (``stsf_gym``, ``stsf_gym.agents``, ...)."""
    folders = []
    for name in CODE_PACKAGES:
        spec = importlib.util.find_spec(name)
        found = (spec.submodule_search_locations or []) if spec else []
        folders += [Path(p).resolve() for p in found]
    return folders


def from_checkout() -> bool:
    """Whether the package runs from a git checkout (an editable install): its folders are
    then source, the repository's to commit."""
    return git_state()["commit"] is not None


def check_ship_to(to: Path) -> None:
    """Fail before any work when ``to`` lies in a folder of the installed package: shipping
    writes to a folder the user names, never into the package. A git checkout's own folders
    are source and may be named (the project ships its agents to
    ``agents/pretrained/trained-models`` of its checkout)."""
    here = Path(to).resolve()
    inside = [folder for folder in package_folders() if here.is_relative_to(folder)]
    if inside and not from_checkout():
        raise ConfigError(
            f"--ship-to {to}: inside the installed package ({inside[0]}), which is only read; "
            "ship to a folder of your own, e.g. --ship-to shipped-agents"
        )


def check_destination(target: Path, replace: bool) -> None:
    """Fail before any work when ``target`` (a shipped agent's folder) exists and ``replace``
    was not asked for, or its suite folder cannot be written."""
    if target.exists() and not replace:
        raise ConfigError(
            f"an agent is already shipped as {target.parent.name}/{target.name} ({target}); "
            "add --replace to replace it whole"
        )
    check_folder(target.parent, "the shipping destination")


def folder_beside(target: Path, tag: str) -> Path:
    """A new, empty folder beside ``target`` (``.<name>.<tag>.<random>``), made as ``mkdir``
    makes one (mode 0o777 less the user's umask; ``tempfile.mkdtemp`` makes it 0o700, which a
    shipped agent renamed from it would keep)."""
    while True:
        folder = target.parent / f".{target.name}.{tag}.{secrets.token_hex(4)}"
        try:
            folder.mkdir()
            return folder
        except FileExistsError:
            continue


def swap_in(built: Path, target: Path) -> None:
    """Put folder ``built`` at ``target`` by renames: the old agent (if any) set aside first,
    removed only once the new one is in place; restored if the second rename fails."""
    aside = None
    if target.exists():
        aside = folder_beside(target, "old")
        os.replace(target, aside / target.name)
    try:
        os.replace(built, target)
    except BaseException:
        if aside is not None:
            os.replace(aside / target.name, target)
            shutil.rmtree(aside, ignore_errors=True)
        raise
    if aside is not None:
        shutil.rmtree(aside, ignore_errors=True)


def saved_val_success(record: dict) -> float | None:
    """The val success of the model a run saved (its ``train.json`` ``record``): the last
    evaluation of its reward stage where one ran, else the demonstrations' kept round."""
    last = record.get("last_evaluation") or {}
    if last.get("timesteps"):
        return last.get("success_rate")
    return (record.get("demonstrations") or {}).get("val_success")


def without_optimizer_moments(source: Path, target: Path) -> None:
    """Copy SB3 model ``source`` to ``target`` with its optimizer's running moments dropped
    (its parameter groups, learning rate included, kept): acting reads none of them, and a
    fine-tuned model's Adam moments are twice its weights. Every other entry is copied as is."""
    with zipfile.ZipFile(source) as src, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename == OPTIMIZER:
                state = torch.load(io.BytesIO(data), map_location="cpu", weights_only=False)
                buffer = io.BytesIO()
                torch.save({"state": {}, "param_groups": state["param_groups"]}, buffer)
                data = buffer.getvalue()
            dst.writestr(item, data)


def build_agent(
    name: str, training: Path, suite: str, records: list[dict], folder: Path, seen_inputs
) -> None:
    """Write shipped agent ``name`` into the empty ``folder``: per seed its model and
    ``train.json``, and ``agent.json`` (``seen_inputs(model, suite, pose source)`` the inputs
    each model sees)."""
    algo, pose_source = trained_algo(records[0]), records[0]["estimator"]
    seen, val = {}, {}
    for record in records:
        seed = record["seed"]
        model = folder / f"seed-{seed}.zip"
        without_optimizer_moments(training / f"seed-{seed}" / MODEL, model)
        write_json(folder / f"seed-{seed}.json", record)
        seen[str(seed)] = seen_inputs(model, suite, pose_source).tolist()
        val[str(seed)] = saved_val_success(record)
    summary = {
        "name": name,
        "algo": algo,
        "suite": suite,
        "pose_source": pose_source,
        "seeds": [r["seed"] for r in records],
        "val_success": val,
        "provenance": {str(r["seed"]): r["made_by"] for r in records},
        "seen": seen,
    }
    write_json(folder / "agent.json", summary)
