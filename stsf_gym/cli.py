"""The ``stsf-gym`` command line. Every command takes ``--seed``, ``--out``, ``--config``,
``--set key=value`` and ``--json`` (a machine-readable result on stdout)."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from stsf_gym.config import ConfigError, parse_overrides


def _common(parser: argparse.ArgumentParser, out: str) -> None:
    parser.add_argument("--seed", type=int, default=0, help="base random seed (default 0)")
    parser.add_argument("--out", type=Path, default=Path(out), help=f"output folder ({out})")
    parser.add_argument("--config", help="YAML config (env: merged over configs/default.yaml)")
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override one config value, e.g. camera.width=640",
    )
    parser.add_argument("--json", action="store_true", help="print the result as JSON on stdout")


def _demo(args: argparse.Namespace) -> dict:
    from stsf_gym.experiments.demo import run_demo

    if args.seconds <= 0:
        raise ConfigError(f"--seconds must be positive, got {args.seconds}")
    summary = run_demo(
        args.out,
        seed=args.seed,
        seconds=args.seconds,
        env_id=args.env,
        config=args.config,
        **parse_overrides(args.overrides),
    )
    for key in ("trace", "last_image"):
        summary.pop(key)
    if not args.json:
        from rich.console import Console
        from rich.table import Table

        table = Table(
            title=f"stsf-gym demo: {summary['env_id']} (seed {summary['seed']}, "
            f"renderer {summary['renderer']})"
        )
        for column in summary["rows"][0]:
            table.add_column(column)
        for row in summary["rows"]:
            table.add_row(*(str(v) for v in row.values()))
        console = Console()
        console.print(table)
        console.print(
            f"{summary['sim_time_s']:.0f} s simulated in {summary['wall_time_s']:.1f} s "
            f"({summary['real_time_factor']:.1f}x real time), outcome: {summary['outcome']}, "
            f"dead-reckoning error {summary['odometry_error_m']:.3f} m. "
            f"Wrote {args.out}/summary.md and {summary['figure']}"
        )
    return summary


def _reproduce(args: argparse.Namespace) -> dict:
    from stsf_gym.experiments.table1 import run_table1

    if args.workers < 1:
        raise ConfigError(f"--workers must be at least 1, got {args.workers}")
    overrides = parse_overrides(args.overrides)
    if args.seeds is not None:
        if args.seeds < 1:
            raise ConfigError(f"--seeds must be at least 1, got {args.seeds}")
        overrides["seeds"] = args.seeds
    out = args.out / args.experiment
    summary = run_table1(out, seed=args.seed, config=args.config, workers=args.workers, **overrides)
    if not args.json:
        from rich.console import Console

        Console().print((out / "table1.md").read_text())
        Console().print(f"Wrote {out}/table1.md, results.json and {summary['figure']}")
    return summary


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="stsf-gym", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    demo = commands.add_parser("demo", help="a short drive down the IRL corridor, with a report")
    _common(demo, "out/demo")
    demo.add_argument("--seconds", type=float, default=90.0, help="simulated seconds (90)")
    demo.add_argument("--env", default="stsf_gym/Corridor-v0", help="environment id")
    demo.set_defaults(run=_demo)
    reproduce = commands.add_parser("reproduce", help="the paper's experiments")
    reproduce.add_argument("experiment", choices=["table1"], help="which experiment")
    _common(reproduce, "out")
    reproduce.add_argument("--seeds", type=int, help="number of seeds (config: 20)")
    reproduce.add_argument("--workers", type=int, default=2, help="parallel processes (2)")
    reproduce.set_defaults(run=_reproduce)
    return parser


def _silence_c_stdout() -> None:
    """Send file descriptor 1 to /dev/null for the rest of the process, keeping Python's
    ``sys.stdout`` on the real stdout: PyBullet's C code prints banners there (some only at
    exit, some in worker processes), which would garble tables and ``--json`` output."""
    sys.stdout.flush()
    real = os.dup(1)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)
    sys.stdout = os.fdopen(real, "w", buffering=1)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    _silence_c_stdout()
    try:
        result = args.run(args)
    except (ConfigError, ValueError) as err:
        print(f"stsf-gym {args.command}: error: {err}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(result, default=lambda v: v.tolist() if hasattr(v, "tolist") else str(v)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
