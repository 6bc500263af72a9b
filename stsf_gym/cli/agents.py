"""``stsf-gym agents``: the agents shipped trained (``pretrained:...``), listed, or a training
folder shipped as one."""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.agents import pretrained
from stsf_gym.envs.suite import suite_names
from stsf_gym.io import markdown_table
from stsf_gym.validation import ConfigError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``agents``."""
    parser.add_argument("--json", action="store_true", help="print the list as JSON on stdout")
    parser.add_argument(
        "--ship", type=Path, help="a `train --seeds N` folder to ship as a pretrained agent"
    )
    parser.add_argument(
        "--suite",
        choices=suite_names(),
        help="with --ship: the suite it was trained on; alone: list this suite's agents only",
    )
    parser.add_argument(
        "--replace",
        action="store_true",
        help="with --ship: replace an agent already shipped under the same name, whole",
    )
    parser.add_argument("--verbose", action="store_true", help="show PyBullet's C banners")


def run(args: argparse.Namespace) -> dict | list:
    """Ship ``--ship`` (and print its name), or list the shipped agents."""
    if args.ship is not None:
        if args.suite is None:
            raise ConfigError("--ship needs --suite: the suite the runs were trained on")
        name = pretrained.ship(args.ship, args.suite, args.replace)
        if not args.json:
            print(f"Shipped {name}")
        return pretrained.summary(name)
    if args.replace:
        raise ConfigError("--replace replaces a shipped agent by --ship: add --ship and --suite")
    rows = [r for r in pretrained.listing() if args.suite in (None, r["suite"])]
    if not args.json:
        table = [
            {
                "name": r["name"],
                "algo": r["algo"],
                "suite": r["suite"],
                "pose source": r["pose_source"],
                "seeds": len(r["seeds"]),
                "val success": ", ".join(f"{v:.2f}" for v in r["val_success"].values()),
                "aliases": ", ".join(a.removeprefix(pretrained.PREFIX) for a in r["aliases"]),
            }
            for r in rows
        ]
        print(markdown_table(table) if table else "No shipped agents.")
    return rows
