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

    _check_counts(args)
    env = _env_overrides(args)
    if args.seconds is not None:
        if args.seconds <= 0:
            raise ConfigError(f"--seconds must be positive, got {args.seconds}")
        env.setdefault("sim", {})["max_episode_seconds"] = args.seconds
    summary = run_demo(args.out, seed=args.seed, workers=args.workers, env=env)
    if not args.json:
        from rich.console import Console
        from rich.table import Table

        table = Table(title=f"stsf-gym demo: follower on the IRL corridor (seed {args.seed})")
        for column in summary["table"][0]:
            table.add_column(column)
        for row in summary["table"]:
            table.add_row(*(f"{v:.3f}" if isinstance(v, float) else str(v) for v in row.values()))
        console = Console()
        console.print(table)
        console.print(
            f"Wrote {args.out}/results.md, results.json and {', '.join(summary['figures'])}"
        )
    return summary


def _check_counts(args: argparse.Namespace) -> None:
    for flag in ("workers", "seeds"):
        value = getattr(args, flag, None)
        if value is not None and value < 1:
            raise ConfigError(f"--{flag} must be at least 1, got {value}")


def _print_markdown(args: argparse.Namespace, path: Path) -> None:
    if not args.json:
        from rich.console import Console

        Console().print(path.read_text())
        Console().print(f"Wrote {path.parent}/")


def _env_overrides(args: argparse.Namespace) -> dict:
    """Env settings from ``--config FILE`` and ``--set key=value`` (later wins)."""
    from envs.config import deep_merge, overrides_to_tree, read_yaml

    base = read_yaml(args.config) if args.config else {}
    return deep_merge(base, overrides_to_tree(parse_overrides(args.overrides)))


def _evaluate(args: argparse.Namespace) -> dict:
    from stsf_gym.estimators import ESTIMATORS
    from stsf_gym.experiments.evaluate import evaluate

    _check_counts(args)
    estimators = [e.strip() for e in args.estimators.split(",") if e.strip()]
    for name in estimators:
        if name not in ESTIMATORS:
            raise ConfigError(f"unknown estimator {name!r}; known: {', '.join(ESTIMATORS)}")
    summary, _ = evaluate(
        args.out,
        estimators,
        args.seeds,
        args.seed,
        args.world,
        args.agent,
        args.workers,
        parse_overrides(args.overrides),
    )
    _print_markdown(args, args.out / "results.md")
    return summary


def _reproduce(args: argparse.Namespace) -> dict:
    from stsf_gym.experiments.figures import fig10, fig11
    from stsf_gym.experiments.table1 import run_table1

    _check_counts(args)
    out = args.out / args.experiment
    if args.experiment in ("fig10", "fig11"):
        run = fig10 if args.experiment == "fig10" else fig11
        summary = run(out, args.seeds or 10, args.seed, args.workers, _env_overrides(args))
        _print_markdown(args, out / f"{args.experiment}.md")
        return summary
    overrides = parse_overrides(args.overrides)
    if args.seeds is not None:
        overrides["seeds"] = args.seeds
    summary = run_table1(out, seed=args.seed, config=args.config, workers=args.workers, **overrides)
    _print_markdown(args, out / "table1.md")
    return summary


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="stsf-gym", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    demo = commands.add_parser("demo", help="the follower on each estimator, IRL corridor")
    _common(demo, "out/demo")
    demo.add_argument("--seconds", type=float, help="simulated time limit per episode")
    demo.add_argument("--workers", type=int, default=2, help="parallel processes (2)")
    demo.set_defaults(run=_demo)
    reproduce = commands.add_parser("reproduce", help="the paper's experiments")
    reproduce.add_argument("experiment", choices=["table1", "fig10", "fig11"])
    _common(reproduce, "out")
    reproduce.add_argument("--seeds", type=int, help="seeds (table1: config, 20; figs: 10)")
    reproduce.add_argument("--workers", type=int, default=2, help="parallel processes (2)")
    reproduce.set_defaults(run=_reproduce)
    evaluate = commands.add_parser("evaluate", help="an agent on each estimator, many seeds")
    _common(evaluate, "out/evaluate")
    evaluate.add_argument("--agent", default="follower", help="agent (follower)")
    evaluate.add_argument(
        "--estimators",
        default="odometry,conventional,stsf,ekf",
        help="comma-separated estimator names",
    )
    evaluate.add_argument("--world", default="irl_corridor", help="world name or YAML path")
    evaluate.add_argument("--seeds", type=int, default=5, help="episodes per estimator (5)")
    evaluate.add_argument("--workers", type=int, default=2, help="parallel processes (2)")
    evaluate.set_defaults(run=_evaluate)
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
