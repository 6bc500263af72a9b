"""The names the benchmark's report gives agents: short, and saying which agent a model is."""

from __future__ import annotations

from pathlib import Path

from stsf_gym.agents import pretrained
from stsf_gym.experiments.benchmark.trained import SEED_FOLDERS


def agent_name(agent: str) -> str:
    """``follower``; a training folder by its name (``ppo-stsf``); a shipped agent by its
    name without the prefix and suite (``pretrained:corridor/ppo-truth`` -> ``ppo-truth``);
    a model by its training folder's or shipped agent's name with its seed
    (``ppo-stsf/seed-0``, ``ppo-truth/seed-0``), or by its file's stem when it is neither.
    The JSON keeps the whole path."""
    path = Path(agent)
    if path.suffix != ".zip":
        return path.name
    folder = path.parent
    if folder.parent.parent.name == pretrained.MODELS.name:  # <models>/<suite>/<agent>/seed-S.zip
        return f"{folder.name}/{path.stem}"
    if path.name != "model.zip":
        return path.stem
    return f"{folder.parent.name}/{folder.name}" if folder.match(SEED_FOLDERS) else folder.name
