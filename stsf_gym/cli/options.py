"""The options several commands share (the common ones, recording, the backend, the world), and
the checks every command's options pass before any work (:func:`preflight`)."""

from __future__ import annotations

import argparse
import difflib
import math
from pathlib import Path

from stsf_gym.config_files import read_yaml
from stsf_gym.io import check_file, check_folder, remove_partial_writes
from stsf_gym.validation import ConfigError

DEFAULT_WORLD = "irl_corridor"  # --world when none is given
DEFAULT_POSE_SOURCE = "truth"  # train --estimator when none is given
ALL_ESTIMATORS = "odometry,conventional,stsf,ekf"  # --estimators when none is given


def whole(text: str) -> int:
    """A count or seed as a user types it (``100``, ``1e6``, ``2048.0``: YAML and Python read
    ``1e6`` as a number, so ``--timesteps 1e6`` is one); a fraction or a word is refused."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        number = float(text)
    except ValueError:
        number = math.nan
    if not math.isfinite(number) or number != int(number):
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}")
    return int(number)


def common(
    parser: argparse.ArgumentParser,
    out: str,
    config_help: str = "YAML config (env: merged over configs/default.yaml)",
    out_help: str = "output folder",
) -> None:
    """``--seed``, ``--out`` (default ``out``), ``--config``, ``--set``, ``--json``,
    ``--verbose``."""
    parser.add_argument("--seed", type=whole, default=0, help="base random seed (default 0)")
    parser.add_argument("--out", type=Path, default=Path(out), help=f"{out_help} ({out})")
    parser.add_argument("--config", help=config_help)
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override one config value, e.g. camera.width=640",
    )
    parser.add_argument("--json", action="store_true", help="print the result as JSON on stdout")
    parser.add_argument(
        "--verbose", action="store_true", help="show PyBullet's C banners (quiet by default)"
    )


def agents(parser: argparse.ArgumentParser, help_text: str, default: str | None = None) -> None:
    """``--agents`` (``--agent`` an alias): the agents a command runs, comma-separated."""
    parser.add_argument("--agents", "--agent", dest="agents", default=default, help=help_text)


def refuse_unknown(parser: argparse.ArgumentParser, words: list[str]) -> None:
    """Before anything else is checked, exit 2 naming the first word of ``words`` (before a
    ``--``) that looks like a long option ``parser`` does not have (neither one of its options
    nor the start of one), with the closest it has: ``--agnets`` (did you mean --agents?)."""
    known = [option for action in parser._actions for option in action.option_strings]
    for word in words[: words.index("--")] if "--" in words else words:
        name = word.split("=")[0]
        if name.startswith("--") and not any(option.startswith(name) for option in known):
            close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
            hint = f" (did you mean {close[0]}?)" if close else ""
            parser.error(f"unknown option {name}{hint}; see {parser.prog} --help")


def record(parser: argparse.ArgumentParser) -> None:
    """``--record`` and ``--record-frames``: each episode as an MCAP log or Rerun recording."""
    parser.add_argument(
        "--record",
        choices=["mcap", "rerun"],
        help="record each episode to OUT/recordings/: mcap (replayable by stsf-gym replay; "
        "Foxglove, ros2 bag, evo) or rerun (.rrd for the Rerun viewer)",
    )
    parser.add_argument(
        "--record-frames",
        choices=["raw", "png", "jpeg"],
        help="with --record mcap: camera frames as raw or png (lossless: a replay gives the "
        "live estimates bit for bit; png is a little smaller and slow to encode) or jpeg "
        "(about 8x smaller; its replay is approximate). Default raw",
    )


def backend(
    parser: argparse.ArgumentParser, workers_help: str = "processes or local Ray CPUs (2)"
) -> None:
    """Where cells run: ``--backend``, ``--address``, ``--workers``."""
    parser.add_argument(
        "--backend",
        choices=["local", "ray"],
        default="local",
        help="where cells run: local processes or Ray tasks (local)",
    )
    parser.add_argument("--address", help="Ray cluster address (default: start Ray locally)")
    parser.add_argument("--workers", type=whole, default=2, help=workers_help)


def world(parser: argparse.ArgumentParser) -> None:
    """``--world`` (a name, a YAML path or ``generated``) and ``--split``."""
    parser.add_argument(
        "--world", help=f"world name, YAML path, or generated (default {DEFAULT_WORLD})"
    )
    parser.add_argument(
        "--split", help="with --world generated: the world-seed split, train or test"
    )


def workers(parser: argparse.ArgumentParser) -> None:
    """``--workers``: parallel processes."""
    parser.add_argument("--workers", type=whole, default=2, help="parallel processes (2)")


#: Options that mean nothing without another (refused rather than ignored): option, needed
#: option (argparse destinations), and why.
NEEDS = (
    (
        "record_frames",
        "record",
        "--record-frames sets how --record stores camera frames; without --record nothing is "
        "recorded: add --record mcap",
    ),
)
#: Options that would silently override one another: option, other option, and why.
EXCLUDES = (
    ("suite", "world", "--suite picks the worlds (the suite's splits): drop --world/--split"),
    ("suite", "split", "--suite picks the worlds (the suite's splits): drop --world/--split"),
)


def preflight(args: argparse.Namespace) -> None:
    """Every command's checks before any work: the seed, the option combinations of
    :data:`NEEDS` and :data:`EXCLUDES`, and ``--out`` (a folder, or the file a command writes);
    then temporary files a killed run left in ``--out`` are removed."""

    def given(option: str) -> bool:
        return getattr(args, option, None) is not None

    if getattr(args, "seed", 0) < 0:  # seeds seed a numpy SeedSequence: non-negative
        raise ConfigError(f"--seed must be at least 0, got {args.seed}")
    if getattr(args, "config", None) is not None and not read_yaml(args.config):
        raise ConfigError(  # missing, unreadable or malformed: named by read_yaml
            f"--config {args.config}: the file is empty, it sets nothing; give the "
            "settings it should hold, or leave --config out"
        )
    for option, needed, reason in NEEDS:
        if given(option) and not given(needed):
            raise ConfigError(reason)
    for option, other, reason in EXCLUDES:
        if given(option) and given(other):
            raise ConfigError(reason)
    if not hasattr(args, "out"):
        return
    if getattr(args, "out_is_file", False):
        check_file(args.out, "--out")
    else:
        check_folder(args.out, "--out")
        remove_partial_writes(args.out)  # left by a run killed mid-write: nothing to resume
