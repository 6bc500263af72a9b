"""``stsf-gym world``: a generated world as world YAML, or a grid of them as one picture."""

from __future__ import annotations

import argparse

from stsf_gym.cli import inputs, options
from stsf_gym.experiments.generated_worlds import plot_world_grid, write_world_yaml
from stsf_gym.validation import ConfigError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``world``."""
    options.common(parser, "world.yaml")
    parser.add_argument(
        "--grid", type=options.whole, help="draw this many worlds from --seed on as one PNG (--out)"
    )
    parser.set_defaults(out_is_file=True)


def run(args: argparse.Namespace) -> dict:
    """Write the world's YAML (or the grid's PNG) to ``--out``."""
    env = inputs.env_overrides(args)
    if args.grid is not None:
        if args.grid < 1:
            raise ConfigError(f"--grid must be at least 1, got {args.grid}")
        seeds = list(range(args.seed, args.seed + args.grid))
        path = plot_world_grid(seeds, args.out, env)
    else:
        path = write_world_yaml(args.seed, args.out, env)
    if not args.json:
        print(f"Wrote {path}")
    return {"path": str(path), "seed": args.seed, "grid": args.grid}
