"""Option values read into what the API takes: lists of names, pose sources, env settings,
the world, the recording setting. Each refuses a value it cannot read (:class:`ConfigError`
naming the option)."""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.cli.options import DEFAULT_WORLD
from stsf_gym.config import parse_overrides
from stsf_gym.config_files import deep_merge
from stsf_gym.envs.config import load_config, overrides_to_tree, read_yaml
from stsf_gym.io import check_folder
from stsf_gym.recording import require_recording
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import check_pose_source


def names(text: str, flag: str, empty_ok: bool = False) -> list[str]:
    """The comma-separated names of ``text`` (given to option ``flag``); none (unless
    ``empty_ok``) is an error, and so is one named twice (its episodes would be run and counted
    twice)."""
    found = [name.strip() for name in text.split(",") if name.strip()]
    if not found and not empty_ok:
        raise ConfigError(f"{flag} names nothing, got {text!r}")
    twice = sorted({name for name in found if found.count(name) > 1})
    if twice:
        raise ConfigError(f"{twice[0]!r} is named twice in {text!r}")
    return found


def pose_sources(text: str, empty_ok: bool = False) -> list[str]:
    """The comma-separated pose sources of ``--estimators``, each checked: a registered name
    or a ``package.module:Class`` estimator."""
    found = names(text, "--estimators", empty_ok)
    for name in found:
        check_pose_source(name)
    return found


def check_counts(args: argparse.Namespace) -> None:
    """``--workers`` and ``--seeds``, where a command has them, at least 1."""
    for flag in ("workers", "seeds"):
        value = getattr(args, flag, None)
        if value is not None and value < 1:
            raise ConfigError(f"--{flag} must be at least 1, got {value}")


def env_overrides(args: argparse.Namespace, world: str | None = None) -> dict:
    """Env settings from ``--config FILE`` and ``--set key=value`` (later wins), validated
    here (on ``world``) so a bad value is named before any work starts."""
    overrides = parse_overrides(args.overrides)
    env = deep_merge(read_yaml(args.config) if args.config else {}, overrides_to_tree(overrides))
    if "world" in env:
        where = "use --world" if hasattr(args, "world") else "it uses its own world"
        raise ConfigError(f"--config/--set cannot change the world of this command ({where})")
    from stsf_gym.envs.generated_env import parse_world  # the simulator: never for a replay

    generated = world is not None and parse_world(world) is not None
    load_config(args.config, world=None if generated else world, **overrides)
    return env


def world(args: argparse.Namespace) -> str:
    """``--world``, or ``generated:<split>`` for ``--world generated --split NAME``."""
    from stsf_gym.envs.generated_env import GENERATED, generated_label  # the simulator, as above

    name = args.world or DEFAULT_WORLD
    if name == GENERATED:
        if args.split is None:
            raise ConfigError("--world generated needs --split train, val or test")
        return generated_label(args.split)
    if args.split is not None:
        raise ConfigError(f"--split is for --world generated, not --world {name}")
    return name


def recording(args: argparse.Namespace, out: Path | None = None) -> dict | None:
    """The ``record`` setting of the episode runners, from ``--record``/``--record-frames``:
    files in ``<out or --out>/recordings/``. Without the ``record`` extra, or with a
    recordings path that cannot be a folder: bad input, before any episode runs."""
    if args.record is None:
        return None
    require_recording(f"--record {args.record}")
    folder = ((out or args.out) / "recordings").absolute()
    check_folder(folder, "--record")
    return {"format": args.record, "frames": args.record_frames or "raw", "folder": str(folder)}
