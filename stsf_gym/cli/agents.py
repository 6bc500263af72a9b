"""``stsf-gym agents``: the agents shipped trained (``pretrained:...``), listed, or a training
folder shipped as one into a folder the user names (``--ship-to DIR``, never the package)."""

from __future__ import annotations

import argparse
from pathlib import Path

from stsf_gym.agents import pretrained
from stsf_gym.agents.pretrained.shipped_folder import summary_of
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
        "--ship-to",
        type=Path,
        metavar="DIR",
        help="with --ship: the shipped-agents folder to ship into (made if missing; its "
        "manifest.json lists each file's sha256); the agent is then named DIR/SUITE/ALGO-SOURCE",
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
        if args.ship_to is None:
            raise ConfigError(
                "--ship needs --ship-to DIR: the folder to ship into (the installed package is "
                "only read), e.g. --ship-to shipped-agents"
            )
        folder = pretrained.ship(args.ship, args.suite, args.ship_to, args.replace)
        summary = summary_of(folder)
        if not args.json:
            print(f"Shipped {summary['name']} to {folder}")
        return summary
    if args.replace or args.ship_to is not None:
        flag = "--replace replaces" if args.replace else "--ship-to is where --ship puts"
        raise ConfigError(f"{flag} a shipped agent by --ship: add --ship and --suite")
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
