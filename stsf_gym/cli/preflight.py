"""Every command's checks before any work: the seed, options that need or exclude another,
an empty ``--config``, and ``--out``."""

from __future__ import annotations

import argparse

from stsf_gym.io import check_file, check_folder, remove_partial_writes
from stsf_gym.validation import ConfigError
from stsf_gym.yaml_layers import read_yaml

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
