"""Model files of saved stable-baselines3 agents: checked, digested and loaded, and what they were
trained on (the agent that drives with one: :class:`~stsf_gym.agents.trained_agent.SB3Agent`).

``stsf-gym train`` stores a ``stsf_meta`` mapping in every saved model (algorithm,
estimator, world, env overrides, policy-input settings, wall time so far); it travels inside
the ``.zip`` with the model, so a model file alone is enough to evaluate it.
"""

from __future__ import annotations

import hashlib
import io
import json
import zipfile
from pathlib import Path

from stsf_gym.agents.training.hyperparams import algorithm_class
from stsf_gym.validation import ConfigError

META_KEY = "stsf_meta"


def check_model_file(path: str | Path) -> Path:
    """``path`` as a Path if it is a file; ConfigError naming it otherwise."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"agent model not found: {path} (train one with `stsf-gym train`)")
    return path


def check_weights(path: str | Path) -> Path:
    """``path`` if every tensor file in it (``policy.pth``, ...) loads as stable-baselines3 loads
    it (``torch.load(weights_only=True)``); ConfigError naming the file and entry otherwise, so
    a model whose weights are corrupt fails before any work, not inside an episode."""
    import torch

    path = check_model_file(path)
    try:
        with zipfile.ZipFile(path) as archive:
            entries = [n for n in archive.namelist() if n.endswith(".pth")]
            if "policy.pth" not in entries:
                raise ConfigError(f"{path} holds no policy.pth: not a stable-baselines3 model")
            for entry in entries:
                try:
                    tensors = io.BytesIO(archive.read(entry))
                    torch.load(tensors, map_location="cpu", weights_only=True)
                except Exception as err:  # torch raises many kinds on a corrupt file
                    raise ConfigError(  # torch's own text would advise weights_only=False
                        f"{path}: its weights ({entry}) cannot be read ({type(err).__name__}): "
                        "the file is corrupt or was not saved by stable-baselines3; train or "
                        "copy it again"
                    ) from None
    except zipfile.BadZipFile as err:
        raise ConfigError(f"{path} is not a stable-baselines3 model: {err}") from None
    return path


def model_digest(path: str | Path) -> str:
    """The first 10 hex digits of the model file's SHA-256 (a retrained model differs)."""
    return hashlib.sha256(check_model_file(path).read_bytes()).hexdigest()[:10]


def _saved_data(path: str | Path) -> dict:
    """The JSON ``data`` part of an SB3 model file (attributes, not the network)."""
    path = check_model_file(path)
    try:
        with zipfile.ZipFile(path) as archive:
            data = json.loads(archive.read("data"))
    except (zipfile.BadZipFile, KeyError, json.JSONDecodeError) as err:
        raise ConfigError(f"{path} is not a stable-baselines3 model: {err}") from None
    if META_KEY not in data:
        raise ConfigError(f"{path} was not saved by `stsf-gym train` (no {META_KEY})")
    return data


def model_metadata(path: str | Path) -> dict:
    """The ``stsf_meta`` mapping saved in a model trained by ``stsf-gym train``."""
    return _saved_data(path)[META_KEY]


def trained_algo(record: dict) -> str:
    """What ran to train a model, from its ``train.json`` (or ``stsf_meta``): the ``algo`` it
    records when that says so (``dagger``, ``dagger+ppo``, ``ppo``, ...); a record written
    before names said what ran holds the SB3 class there (``ppo``), read from its stages:
    demonstrations and no reward step are ``dagger``, both are ``dagger+<class>``."""
    algo = record["algo"]
    if algo.startswith("dagger") or not record.get("demonstrations"):
        return algo
    reward_steps = (record.get("hyperparams") or {}).get("n_timesteps", 0)
    return f"dagger+{algo}" if reward_steps else "dagger"


def training_record(path: str | Path) -> dict:
    """What an evaluation records about a model: algorithm, pose source, world, timesteps. A
    ``dagger+...`` run's model saved before its first reward step (its clone) ran ``dagger``."""
    data = _saved_data(path)
    meta = data[META_KEY]
    algo = trained_algo(meta)
    return {
        "algo": "dagger" if algo.startswith("dagger+") and not data["num_timesteps"] else algo,
        "estimator": meta["estimator"],
        "world": meta["world"],
        "timesteps": data["num_timesteps"],
        "digest": model_digest(path),
    }


def load_model(path: str | Path, env=None):
    """The saved model (its algorithm read from its metadata), on the CPU."""
    meta = model_metadata(path)
    return algorithm_class(meta["algo"]).load(str(path), env=env, device="cpu")
