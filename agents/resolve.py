"""One reading of agent names, for every command and :func:`~stsf_gym.agents.registry.make_agent`.

A name the CLI takes stands for one or more single agents, one per trained model:

- ``pretrained:<suite>/<algo>-<pose source>`` (or an alias of one, :mod:`stsf_gym.agents.
  pretrained`): the model of each of its training seeds;
- a training folder (the ``OUT`` of ``stsf-gym train``): its ``seed-*/model.zip``, or the
  ``model.zip`` of a one-seed run, taken whole (:mod:`~stsf_gym.agents.training_folder`: an
  unfinished or misnamed seed is refused by name);
- a ``.zip`` model file: itself, as an absolute path;
- anything else (``follower``, ``cautious-follower``, a registered name, ``package.module:Class``):
  itself; :func:`~stsf_gym.agents.registry.make_agent` judges it.

:func:`resolve_agent` is that reading; the benchmark's ``expand_agents`` and ``make_agent`` both
call it, so a name means the same models everywhere.
"""

from __future__ import annotations

from pathlib import Path

from stsf_gym.agents import pretrained
from stsf_gym.agents.training_folder import SEED_FOLDERS, folder_models


def resolve_agent(name: str) -> list[str]:
    """The single agents ``name`` stands for (see the module's docstring): model files as
    absolute paths, in training-seed order; any other name as given."""
    path = Path(name)
    if name.startswith(pretrained.PREFIX):
        return [str(model) for model in pretrained.models(name)]
    if path.is_dir():
        return [str(model.resolve()) for model in folder_models(path)]
    if path.suffix == ".zip":
        return [str(path.resolve())]
    return [name]


def training_group(agent: str) -> str | None:
    """The agent a model file is one training seed of: its shipped name (canonical), or its
    training folder; None for an agent by name."""
    if not agent.endswith(".zip"):
        return None
    shipped = pretrained.shipped_name(agent)
    if shipped is not None:
        return shipped
    folder = Path(agent).parent
    return str(folder.parent if folder.match(SEED_FOLDERS) else folder)
