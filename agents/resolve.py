"""One reading of agent names, for every command and :func:`~stsf_gym.agents.registry.make_agent`.

A name the CLI takes stands for one or more single agents, one per trained model:

- ``pretrained:<suite>/<algo>-<pose source>`` (or an alias of one, :mod:`stsf_gym.agents.
  pretrained`): the model of each of its training seeds;
- a shipped agent's folder in a folder of shipped agents (``DIR/<suite>/<algo>-<pose source>``,
  as ``stsf-gym agents --ship ... --ship-to DIR`` writes it): the model of each of its seeds,
  each checked against ``DIR/manifest.json`` (:mod:`~stsf_gym.agents.pretrained.shipped_folder`);
- a training folder (the ``OUT`` of ``stsf-gym train``): its ``seed-*/model.zip``, or the
  ``model.zip`` of a one-seed run, taken whole (:mod:`~stsf_gym.agents.training_folder`: an
  unfinished or misnamed seed is refused by name);
- ``clone:<training folder>``: the clone of each of its runs, the policy each reward stage
  started from (``seed-S/finetune/clone.zip``), so a fine-tuned agent and its own start are
  scored side by side, over the same seeds;
- a ``.zip`` model file: itself;
- anything else (``follower``, ``cautious-follower``, a registered name, ``package.module:Class``):
  itself; :func:`~stsf_gym.agents.registry.make_agent` judges it.

:func:`resolve_agent` is that reading; the benchmark's ``expand_agents`` and ``make_agent`` both
call it, so a name means the same models everywhere. A model file under the working directory
is named relative to it (:func:`model_path`), so the cells and results of a run started from a
clone's root name no path of this machine: they are committed, and reused by the same run from
another clone.
"""

from __future__ import annotations

from pathlib import Path

from stsf_gym.agents import pretrained
from stsf_gym.agents.pretrained.shipped_folder import checked_models, is_agent_folder
from stsf_gym.agents.training_folder import CLONE, SEED_FOLDERS, folder_models, seed_runs
from stsf_gym.validation import ConfigError

CLONE_PREFIX = "clone:"


def resolve_agent(name: str) -> list[str]:
    """The single agents ``name`` stands for (see the module's docstring): model files as
    :func:`model_path` names them, in training-seed order; any other name as given."""
    path = Path(name)
    if name.startswith(pretrained.PREFIX):
        return [model_path(model) for model in pretrained.models(name)]
    if name.startswith(CLONE_PREFIX):
        return [model_path(clone) for clone in folder_clones(name.removeprefix(CLONE_PREFIX))]
    if path.is_dir() and is_agent_folder(path):
        return [model_path(model) for model in checked_models(path)]
    if path.is_dir():
        return [model_path(model) for model in folder_models(path)]
    if path.suffix == ".zip":
        return [model_path(path)]
    return [name]


def model_path(model: Path) -> str:
    """``model``'s path relative to the working directory when it lies under it (the same
    file from any clone run at its root; job workers, local processes or a local Ray, share
    the working directory), else absolute."""
    try:
        absolute, here = model.resolve(), Path.cwd().resolve()
    except (RuntimeError, OSError) as err:  # a symlink loop (RuntimeError before Python 3.13)
        raise ConfigError(f"model {model} cannot be followed: {err}") from None
    return str(absolute.relative_to(here) if absolute.is_relative_to(here) else absolute)


def folder_clones(folder: str | Path) -> list[Path]:
    """The clone of each run of training folder ``folder`` (``seed-S/finetune/clone.zip``, or
    its own for one run); a run without one (trained without a reward stage, or before it)
    raises :class:`ConfigError` naming it."""
    runs = [run for _, run in seed_runs(folder)] or [Path(folder)]
    clones = [run / CLONE for run in runs]
    for clone in clones:
        if not clone.is_file():
            raise ConfigError(
                f"{CLONE_PREFIX}{folder}: {clone} not found; only a run with a reward stage "
                "(`stsf-gym train --algo dagger+ppo`) keeps the clone it started from"
            )
    return clones


def training_group(agent: str) -> str | None:
    """The agent a model file is one training seed of: its shipped name (canonical), its
    training folder, or ``clone:<training folder>`` for a run's clone; None for an agent by
    name."""
    if not agent.endswith(".zip"):
        return None
    shipped = pretrained.shipped_name(agent)
    if shipped is not None:
        return shipped
    path = Path(agent)
    if path.match(f"*/{CLONE}"):
        return CLONE_PREFIX + _run_folder(path.parent.parent)
    return _run_folder(path.parent)


def _run_folder(run: Path) -> str:
    """The training folder of ``run``: its parent for a ``seed-S`` run, else itself."""
    return str(run.parent if run.match(SEED_FOLDERS) else run)
