"""The ``stsf-gym`` command line. Every command takes ``--seed``, ``--out``, ``--config``,
``--set key=value``, ``--json`` (a machine-readable result on stdout) and ``--verbose``
(PyBullet's C banners, quiet by default)."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from stsf_gym.config import ConfigError, parse_overrides
from stsf_gym.io import check_file, check_folder, remove_partial_writes
from stsf_gym.results.provenance import set_command
from stsf_gym.validation import FieldError, Range, check_number

DEFAULT_WORLD = "irl_corridor"  # --world when none is given
DEFAULT_POSE_SOURCE = "truth"  # train --estimator when none is given


def _common(
    parser: argparse.ArgumentParser,
    out: str,
    config_help: str = "YAML config (env: merged over configs/default.yaml)",
    out_help: str = "output folder",
) -> None:
    parser.add_argument("--seed", type=int, default=0, help="base random seed (default 0)")
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


def _demo(args: argparse.Namespace) -> dict:
    from stsf_gym.experiments.demo import COLUMNS, run_demo
    from stsf_gym.results import rendered

    _check_counts(args)
    env = _env_overrides(args)
    if args.seconds is not None:
        if args.seconds <= 0:
            raise ConfigError(f"--seconds must be positive, got {args.seconds}")
        if "max_episode_seconds" in env.get("sim", {}):
            raise ConfigError(
                "--seconds and sim.max_episode_seconds (from --config or --set) both set the "
                "episode length; give one"
            )
        env.setdefault("sim", {})["max_episode_seconds"] = args.seconds
    if args.video_seconds is not None and args.video_seconds < 0:
        raise ConfigError(f"--video-seconds must be >= 0, got {args.video_seconds}")
    summary = run_demo(
        args.out, args.seed, args.workers, env, args.video_seconds, args.seeds, _recording(args)
    )
    if not args.json:
        from rich.console import Console

        from stsf_gym.terminal_table import fit_table

        console = Console()
        seeds = f"seed {args.seed}" if args.seeds == 1 else f"{args.seeds} seeds from {args.seed}"
        title = f"stsf-gym demo: follower on the IRL corridor ({seeds})"
        cells = [rendered(row, COLUMNS) for row in summary["rows"]]
        rows = [list(row.values()) for row in cells]
        console.print(fit_table(list(cells[0]), rows, console.width, title, "results.md"))
        videos = [str(args.out / v) for v in summary.get("videos", {}).values()]
        console.print(
            f"Wrote {args.out}/results.md, results.json, {', '.join(summary['figures'])}"
            + (f" and {', '.join(videos)}" if videos else "")
        )
    return summary


def _record_args(parser: argparse.ArgumentParser) -> None:
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


def _recording(args: argparse.Namespace, out: Path | None = None) -> dict | None:
    """The ``record`` setting of the episode runners, from ``--record``/``--record-frames``:
    files in ``<out or --out>/recordings/``. Without the ``record`` extra, or with a
    recordings path that cannot be a folder: bad input, before any episode runs."""
    if args.record is None:
        return None
    from stsf_gym.recording import require_recording

    require_recording(f"--record {args.record}")
    folder = ((out or args.out) / "recordings").absolute()
    check_folder(folder, "--record")
    return {"format": args.record, "frames": args.record_frames or "raw", "folder": str(folder)}


def _replay(args: argparse.Namespace) -> dict:
    from stsf_gym.recording import require_recording

    require_recording("stsf-gym replay")
    from stsf_gym.experiments.replay import replay_logs

    if args.config or args.overrides:
        raise ConfigError("replay runs the logs as recorded: it takes no --config or --set")
    estimators = _pose_sources(args.estimators)
    summary = replay_logs(args.files, estimators, args.out)
    _print_markdown(args, args.out / "results.md")
    return summary


def _check_counts(args: argparse.Namespace) -> None:
    for flag in ("workers", "seeds"):
        value = getattr(args, flag, None)
        if value is not None and value < 1:
            raise ConfigError(f"--{flag} must be at least 1, got {value}")


def _print_markdown(args: argparse.Namespace, path: Path) -> None:
    if not args.json:
        from rich.console import Console

        from stsf_gym.terminal_table import print_markdown

        console = Console()
        print_markdown(path.read_text(), console, path.name)
        console.print(f"Wrote {path.parent}/")


def _env_overrides(args: argparse.Namespace, world: str | None = None) -> dict:
    """Env settings from ``--config FILE`` and ``--set key=value`` (later wins), validated
    here (on ``world``) so a bad value is named before any work starts."""
    from stsf_gym.envs.config import deep_merge, load_config, overrides_to_tree, read_yaml

    overrides = parse_overrides(args.overrides)
    env = deep_merge(read_yaml(args.config) if args.config else {}, overrides_to_tree(overrides))
    if "world" in env:
        where = "use --world" if hasattr(args, "world") else "it uses its own world"
        raise ConfigError(f"--config/--set cannot change the world of this command ({where})")
    from stsf_gym.envs.generated_env import parse_world

    generated = world is not None and parse_world(world) is not None
    load_config(args.config, world=None if generated else world, **overrides)
    return env


def _world(args: argparse.Namespace) -> str:
    """``--world``, or ``generated:<split>`` for ``--world generated --split NAME``."""
    from stsf_gym.envs.generated_env import GENERATED, generated_label

    world = args.world or DEFAULT_WORLD
    if world == GENERATED:
        if args.split is None:
            raise ConfigError("--world generated needs --split train, val or test")
        return generated_label(args.split)
    if args.split is not None:
        raise ConfigError(f"--split is for --world generated, not --world {world}")
    return world


def _world_cmd(args: argparse.Namespace) -> dict:
    from stsf_gym.experiments.generated_worlds import plot_world_grid, write_world_yaml

    env = _env_overrides(args)
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


def _expanded(names: list[str]) -> list[str]:
    """Training folders and shipped agents (``pretrained:...``) as their models, one per seed."""
    from stsf_gym.experiments.benchmark.trained import expand_agents

    return expand_agents(names)


def _agents(args: argparse.Namespace) -> dict | list:
    from stsf_gym.agents import pretrained
    from stsf_gym.io import markdown_table

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


def _check_agents(names: list[str]) -> None:
    """Make each agent once, so a missing model file or an unknown name fails before any work."""
    from stsf_gym.agents.registry import make_agent

    for name in names:
        make_agent(name)


def _evaluate(args: argparse.Namespace) -> dict:
    from stsf_gym.experiments.evaluate import evaluate

    _check_counts(args)
    estimators = _pose_sources(args.estimators)
    args.world = _world(args)
    agents = _expanded(_names(args.agent, "--agent"))
    _check_agents(sorted({a.replace("{estimator}", e) for a in agents for e in estimators}))
    if len(agents) > 1 or "{estimator}" in args.agent:
        from stsf_gym.experiments.compare import compare

        if args.record:
            raise ConfigError("--record records one agent's episodes, not a comparison")
        summary = compare(
            args.out,
            agents,
            estimators,
            args.seeds,
            args.seed,
            args.world,
            args.workers,
            _env_overrides(args, args.world),
        )
        _print_markdown(args, args.out / "comparison.md")
        return summary
    summary, _ = evaluate(
        args.out,
        estimators,
        args.seeds,
        args.seed,
        args.world,
        args.agent,
        args.workers,
        _env_overrides(args, args.world),
        args.faults,
        record=_recording(args),
    )
    _print_markdown(args, args.out / "results.md")
    return summary


def _reproduce(args: argparse.Namespace) -> dict:
    from stsf_gym.experiments.figures import fig10, fig11
    from stsf_gym.experiments.table1.run import run_table1

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


def _train(args: argparse.Namespace) -> dict:
    from stsf_gym.agents.training.train import train

    args.world = _world(args)
    if args.seeds < 1:
        raise ConfigError(f"--seeds must be at least 1, got {args.seeds}")
    if args.estimators is not None and args.estimator is not None:
        raise ConfigError(
            "--estimator names one run's pose source, --estimators a campaign's: give one"
        )
    args.estimator = args.estimator or DEFAULT_POSE_SOURCE
    _check_training_runs(args)
    shared = {
        "algo": args.algo,
        "timesteps": args.timesteps,
        "world": args.world,
        "config": args.config,
        "overrides": parse_overrides(args.overrides),
        "n_envs": args.n_envs,
        "suite": args.suite,
    }
    seeds = range(args.seed, args.seed + args.seeds)
    if args.estimators is not None:  # the cross product: OUT/<pose source>/seed-<s>/
        return _campaign(args, shared, seeds)
    if args.backend != "local" or args.address is not None:
        raise ConfigError("--backend and --address are for a campaign (--estimators)")
    runs = []
    for seed in seeds:
        out = args.out / f"seed-{seed}" if args.seeds > 1 else args.out
        try:
            summary = train(
                **shared, estimator=args.estimator, out=out, seed=seed, progress_bar=not args.json
            )
        except KeyboardInterrupt:
            print(
                f"interrupted: rerun the same command to resume from the last round or update "
                f"saved in {out}",
                file=sys.stderr,
            )
            raise SystemExit(130) from None
        runs.append(summary)
        if not args.json:
            print(_run_line(args.estimator, seed, summary, out))
    return runs[0] if len(runs) == 1 else {"runs": runs}


def _check_training_runs(args: argparse.Namespace) -> None:
    """Before any training: the seeds in range, and each run's folder free of another kind
    of run's trained work (:mod:`stsf_gym.agents.training.preflight`)."""
    from stsf_gym.agents.training.preflight import check_out, check_seeds, run_kind
    from stsf_gym.agents.training.settings import resolve_run

    check_seeds(args.seed, args.seeds)
    seeds = range(args.seed, args.seed + args.seeds)
    if args.estimators is not None:
        runs = [
            (e, s, args.out / e / f"seed-{s}")
            for e in _pose_sources(args.estimators)
            for s in seeds
        ]
    else:
        runs = [
            (args.estimator, s, args.out / f"seed-{s}" if args.seeds > 1 else args.out)
            for s in seeds
        ]
    overrides = parse_overrides(args.overrides)
    for estimator, seed, out in runs:
        run = resolve_run(  # every setting checked; the algorithm as the run will record it
            args.algo, estimator, args.timesteps, seed, args.world, args.config, overrides,
            args.n_envs, args.suite,
        )  # fmt: skip
        check_out(out, run_kind(run.algo, estimator, args.world, args.suite))


def _campaign(args: argparse.Namespace, shared: dict, seeds: range) -> dict:
    """``train --estimators``: every (pose source, seed) run, skipped when finished, on the
    backend asked for (:mod:`stsf_gym.experiments.campaign`)."""
    from tqdm import tqdm

    from stsf_gym.experiments.campaign import campaign_jobs, run_campaign

    if args.workers < 1:
        raise ConfigError(f"--workers must be at least 1, got {args.workers}")
    jobs = campaign_jobs(shared, args.out, _pose_sources(args.estimators), seeds)
    bar = tqdm(total=len(jobs), desc="campaign", unit="run")

    def done(job: dict, summary: dict) -> None:
        bar.update()
        if not args.json:
            bar.write(_run_line(job["estimator"], job["seed"], summary, job["out"]))

    try:
        runs = run_campaign(jobs, args.backend, args.workers, args.address, done)
    except KeyboardInterrupt:
        print(f"interrupted: rerun the same command to resume ({args.out})", file=sys.stderr)
        raise SystemExit(130) from None
    finally:
        bar.close()
    return {"runs": runs}


def _run_line(estimator: str, seed: int, summary: dict, out: Path) -> str:
    """A finished training run in one line."""
    return (
        f"{estimator} seed {seed} ({summary['algo']}): {summary['timesteps']} reward timesteps, "
        f"{summary['wall_time_s']:.0f} s of training; {_evaluation_line(summary)}. "
        f"Wrote {summary['model']}, {summary['learning_curve']}, {out}/train.json"
    )


def _evaluation_line(summary: dict) -> str:
    """A training run's last evaluation in words: RL's (none runs before ``eval_freq`` steps),
    else the demonstration stage's last round."""
    last, stage = summary["last_evaluation"], summary.get("demonstrations")
    if last is not None:
        rate = last["success_rate"]
        return f"last evaluation (at {last['timesteps']} timesteps): success rate {rate:.2f}"
    if stage is not None:
        return (
            f"demonstrations, {stage['round']} rounds, kept round {stage['kept_round']}: "
            f"val success {stage['val_success']:.2f}"
        )
    return "no evaluation ran (fewer timesteps than eval_freq)"


def _sweep(args: argparse.Namespace) -> dict:
    from stsf_gym.experiments.sweep.run import run_sweep

    _check_counts(args)
    out = args.out / args.file.stem
    summary = run_sweep(
        args.file, out, args.backend, args.workers, args.address, args.seed, _env_overrides(args)
    )
    _print_markdown(args, out / "results.md")
    return _failed_cells(summary, finished=summary["finished"])


def _accuracy_curve(args: argparse.Namespace) -> dict:
    from stsf_gym.estimators import make_estimator
    from stsf_gym.experiments.curve.run import accuracy_curve

    _check_counts(args)
    agents = _expanded(_names(args.agent, "--agent"))
    estimators = _pose_sources(args.estimators, empty_ok=True)  # points on the curve: optional
    _check_agents(agents)
    try:
        levels = [float(level) for level in _names(args.levels, "--levels")]
    except ValueError as err:
        raise ConfigError(f"--levels must be comma-separated numbers, got {args.levels!r}") from err
    for level in levels:  # scales of the dial's errors
        check_number(level, "--levels", Range(ge=0))
    dial = parse_overrides(args.dial)
    if "scale" in dial:  # each level sets it: a --dial scale would change nothing
        raise ConfigError(
            f"--dial scale={dial['scale']}: the dial's scale is what --levels lists "
            f"(--levels {dial['scale']}); --dial sets the dial's other options"
        )
    make_estimator("degraded-truth", **dial)  # a bad dial option fails before any work
    world = args.world or DEFAULT_WORLD
    env = _env_overrides(args, None if args.suite else world)
    if args.suite:
        from stsf_gym.envs.config import deep_merge
        from stsf_gym.envs.generated_env import check_distinct_worlds
        from stsf_gym.envs.suite import load_suite
        from stsf_gym.experiments.benchmark.run import WORLD

        suite = load_suite(args.suite)
        seeds = range(args.seed, args.seed + args.seeds)
        test_worlds = suite.generator_config().split_range("test")
        check_distinct_worlds(test_worlds, seeds, f"--seed {args.seed} --seeds {args.seeds}")
        world, env = WORLD, deep_merge(suite.episode_env, env)
    summary = accuracy_curve(
        args.out,
        agents,
        world,
        args.seeds,
        args.seed,
        levels,
        estimators,
        args.backend,
        args.workers,
        args.address,
        env,
        dial,
        args.suite,
    )
    _print_markdown(args, args.out / "curve.md")
    finished = len(summary["estimators"]) + sum(len(c["levels"]) for c in summary["curves"])
    return _failed_cells(summary, finished)


def _benchmark(args: argparse.Namespace) -> dict:
    from stsf_gym.experiments.benchmark.run import benchmark

    _check_counts(args)
    if args.worlds < 1:
        raise ConfigError(f"--worlds must be at least 1, got {args.worlds}")
    if args.config or args.overrides:
        raise ConfigError("benchmark runs a suite as written: edit or copy its configs/suites file")
    from stsf_gym.experiments.benchmark.trained import expand_agents

    estimators = None if args.estimators is None else _pose_sources(args.estimators)
    agents = expand_agents(_names(args.agents, "--agents"))
    _check_agents(agents)
    summary = benchmark(
        args.out / args.suite,
        args.suite,
        agents,
        estimators,
        args.worlds,
        args.seed,
        args.backend,
        args.workers,
        args.address,
        _recording(args, args.out / args.suite),
    )
    _print_markdown(args, args.out / args.suite / "leaderboard.md")
    return _failed_cells(summary, finished=len(summary["rows"]))


class NothingFinished(RuntimeError):
    """Every cell of a command failed: its files are written, the command exits 1."""


def _failed_cells(summary: dict, finished: int) -> dict:
    """Name each failed cell of ``summary`` on stderr; with ``finished`` results none (every
    cell failed), raise :class:`NothingFinished`."""
    for failed in summary["failed"]:
        print(f"failed cell {json.dumps(failed['cell'])}: {failed['error']}", file=sys.stderr)
    if summary["failed"] and not finished:
        raise NothingFinished(
            f"all {len(summary['failed'])} cell(s) failed (named above): nothing to score; "
            "the report written says so, and a rerun retries them"
        )
    return summary


def _names(text: str, flag: str, empty_ok: bool = False) -> list[str]:
    """The comma-separated names of ``text`` (given to option ``flag``); none (unless
    ``empty_ok``) is an error, and so is one named twice (its episodes would be run and counted
    twice)."""
    names = [name.strip() for name in text.split(",") if name.strip()]
    if not names and not empty_ok:
        raise ConfigError(f"{flag} names nothing, got {text!r}")
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise ConfigError(f"{twice[0]!r} is named twice in {text!r}")
    return names


def _pose_sources(text: str, empty_ok: bool = False) -> list[str]:
    """The comma-separated pose sources of ``--estimators``, each checked: a registered name
    or a ``package.module:Class`` estimator."""
    from stsf_gym.wrappers import check_pose_source

    names = _names(text, "--estimators", empty_ok)
    for name in names:
        check_pose_source(name)
    return names


def _bench(args: argparse.Namespace) -> dict:
    from stsf_gym.bench import run_bench, run_step_bench
    from stsf_gym.bench.step import check_baseline

    if args.seconds <= 0 or min(args.vector_steps, args.steps, args.rounds) < 1:
        raise ConfigError(
            "--seconds must be positive, --vector-steps, --steps and --rounds at least 1"
        )
    if args.baseline is not None:
        check_baseline(args.baseline)
    if args.step_only:
        summary = run_step_bench(args.out, args.steps, args.seed, args.baseline, args.rounds)
    else:
        summary = run_bench(
            args.out, args.seconds, args.vector_steps, args.seed, args.baseline, args.rounds
        )
    _print_markdown(args, args.out / "bench.md")
    return summary


def _backend_args(
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
    parser.add_argument("--workers", type=int, default=2, help=workers_help)


def _world_args(parser: argparse.ArgumentParser) -> None:
    """``--world`` (a name, a YAML path or ``generated``) and ``--split``."""
    parser.add_argument(
        "--world", help=f"world name, YAML path, or generated (default {DEFAULT_WORLD})"
    )
    parser.add_argument(
        "--split", help="with --world generated: the world-seed split, train or test"
    )


def build_parser() -> argparse.ArgumentParser:
    """The ``stsf-gym`` argument parser: one sub-command per entry point, each with its options."""
    from stsf_gym.envs.suite import suite_names

    parser = argparse.ArgumentParser(prog="stsf-gym", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    demo = commands.add_parser("demo", help="the follower on each estimator, IRL corridor")
    _common(demo, "out/demo")
    demo.add_argument("--seconds", type=float, help="simulated time limit per episode")
    demo.add_argument("--seeds", type=int, default=1, help="episodes per estimator (1)")
    demo.add_argument("--workers", type=int, default=2, help="parallel processes (2)")
    demo.add_argument(
        "--video-seconds",
        type=float,
        help="simulated seconds of each estimator's episode in its video (default: the whole "
        "route, ten times faster than simulated time; 0: no videos)",
    )
    _record_args(demo)
    demo.set_defaults(run=_demo)
    reproduce = commands.add_parser("reproduce", help="the paper's experiments")
    reproduce.add_argument("experiment", choices=["table1", "fig10", "fig11"])
    _common(reproduce, "out")
    reproduce.add_argument("--seeds", type=int, help="seeds (table1: config, 20; figs: 10)")
    reproduce.add_argument("--workers", type=int, default=2, help="parallel processes (2)")
    reproduce.set_defaults(run=_reproduce)
    evaluate = commands.add_parser("evaluate", help="an agent on each estimator, many seeds")
    _common(evaluate, "out/evaluate")
    evaluate.add_argument(
        "--agent",
        default="follower",
        help="follower, cautious-follower, a model saved by train (DIR/model.zip), a train "
        "--seeds folder or a shipped agent (pretrained:SUITE/ALGO-SOURCE); several, "
        "comma-separated, give one "
        "comparison table; {estimator} in a path is replaced by each pose source",
    )
    evaluate.add_argument(
        "--estimators",
        default="odometry,conventional,stsf,ekf",
        help="comma-separated pose sources: odometry, conventional (the paper's: current pair "
        "only), conventional-filter, stsf, ekf, smoother, mcl, truth, degraded-truth, or your "
        "own as package.module:Class (e.g. examples.complementary:ComplementaryFilter)",
    )
    _world_args(evaluate)
    evaluate.add_argument("--seeds", type=int, default=5, help="episodes per estimator (5)")
    evaluate.add_argument("--workers", type=int, default=2, help="parallel processes (2)")
    evaluate.add_argument(
        "--faults",
        nargs="+",
        type=Path,
        metavar="FILE",
        help="fault files (e.g. configs/faults/*.yaml): each fault set x each estimator",
    )
    _record_args(evaluate)
    evaluate.set_defaults(run=_evaluate)
    replay = commands.add_parser(
        "replay", help="pose sources rerun on recorded MCAP logs (no simulator)"
    )
    replay.add_argument("files", nargs="+", type=Path, metavar="FILE.mcap", help="MCAP logs")
    _common(replay, "out/replay")
    replay.add_argument(
        "--estimators",
        default="odometry,conventional,stsf,ekf",
        help="comma-separated pose sources (as evaluate's)",
    )
    replay.set_defaults(run=_replay)
    from stsf_gym.agents.training.hyperparams import METHODS

    train = commands.add_parser("train", help="a learnt agent on one pose source")
    _common(train, "out/train", "hyper-parameter YAML (default configs/agents/<learner>.yaml)")
    train.add_argument(
        "--algo",
        choices=list(METHODS),
        default="ppo",
        help="dagger: cloning + DAgger rounds; dagger+ppo: then PPO on the reward; ppo, sac: "
        "reward (ppo: after the demonstrations if the settings enable them) (ppo)",
    )
    train.add_argument(
        "--estimator", help=f"pose source the agent drives on ({DEFAULT_POSE_SOURCE})"
    )
    train.add_argument(
        "--estimators",
        help="a campaign: one run per pose source (comma-separated) and seed, each in "
        "OUT/<pose source>/seed-<s>/; a rerun resumes where it stopped",
    )
    train.add_argument("--timesteps", type=int, help="total env steps (hyper-parameter file)")
    train.add_argument("--n-envs", type=int, help="parallel envs (hyper-parameter file)")
    train.add_argument(
        "--seeds", type=int, default=1, help="training seeds SEED.. (1); each in OUT/seed-<s>/"
    )
    _world_args(train)
    _backend_args(train, "a campaign's runs at once on a local Ray (2; locally one at a time)")
    train.add_argument(
        "--suite",
        choices=suite_names(),
        help="train on a benchmark suite's train worlds and task, evaluate on its val worlds",
    )
    train.set_defaults(run=_train)
    sweep = commands.add_parser("sweep", help="a grid of evaluation or training cells")
    sweep.add_argument("file", type=Path, help="sweep YAML, e.g. configs/sweeps/noise.yaml")
    _common(sweep, "out/sweeps")
    _backend_args(sweep)
    sweep.set_defaults(run=_sweep)
    curve = commands.add_parser(
        "accuracy-curve", help="success against localization error: how good must it be?"
    )
    _common(curve, "out/accuracy_curve")
    curve.add_argument(
        "--agent",
        default="follower",
        help="follower, cautious-follower, saved models, train --seeds folders and/or shipped "
        "agents "
        "(pretrained:SUITE/ALGO-SOURCE: one curve per training seed), comma-separated",
    )
    curve.add_argument(
        "--world", help=f"world name or YAML path (default {DEFAULT_WORLD}; not with --suite)"
    )
    curve.add_argument(
        "--suite",
        choices=suite_names(),
        help="a benchmark suite's test worlds and declared-stop task instead of --world",
    )
    curve.add_argument("--seeds", type=int, default=3, help="episodes per point (3)")
    curve.add_argument(
        "--levels",
        default="0.5,1,2,4,6,8,11,16",
        help="dial levels: scales of configs/estimators/degraded-truth.yaml's errors",
    )
    curve.add_argument(
        "--dial",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a degraded-truth option, e.g. latency_s=0.3 or rate_hz=2",
    )
    curve.add_argument(
        "--estimators",
        default="odometry,conventional,stsf,ekf",
        help="estimators placed as points on the curve (comma-separated; '' for none)",
    )
    _backend_args(curve)
    curve.set_defaults(run=_accuracy_curve)
    bench_suite = commands.add_parser(
        "benchmark", help="agents x pose sources on a suite's test worlds: the leaderboard"
    )
    _common(bench_suite, "out/benchmark", out_help="output folder: the results go to OUT/<suite>/")
    bench_suite.add_argument("--suite", required=True, choices=suite_names(), help="difficulty")
    bench_suite.add_argument(
        "--agents",
        default="follower",
        help="follower, cautious-follower, saved models, training folders (train --seeds N) "
        "and/or shipped agents (pretrained:SUITE/ALGO-SOURCE), comma-separated; a model drives "
        "on the pose source it was trained on",
    )
    bench_suite.add_argument(
        "--estimators",
        help="pose sources, comma-separated: every agent drives on each (a learnt agent "
        "trained on one, deployed on each); without it, a learnt agent drives on its own and "
        "the follower on odometry, conventional, conventional-filter, stsf and ekf",
    )
    bench_suite.add_argument("--worlds", type=int, default=100, help="test worlds (100)")
    _backend_args(bench_suite)
    _record_args(bench_suite)
    bench_suite.set_defaults(run=_benchmark)
    world = commands.add_parser(
        "world", help="a generated world as world YAML (--seed N), or a grid of them (--grid)"
    )
    _common(world, "world.yaml")
    world.add_argument(
        "--grid", type=int, help="draw this many worlds from --seed on as one PNG (--out)"
    )
    world.set_defaults(run=_world_cmd, out_is_file=True)
    shipped = commands.add_parser("agents", help="the agents shipped trained (pretrained:...)")
    shipped.add_argument("--json", action="store_true", help="print the list as JSON on stdout")
    shipped.add_argument(
        "--ship", type=Path, help="a `train --seeds N` folder to ship as a pretrained agent"
    )
    shipped.add_argument(
        "--suite",
        choices=suite_names(),
        help="with --ship: the suite it was trained on; alone: list this suite's agents only",
    )
    shipped.add_argument(
        "--replace",
        action="store_true",
        help="with --ship: replace an agent already shipped under the same name, whole",
    )
    shipped.add_argument("--verbose", action="store_true", help="show PyBullet's C banners")
    shipped.set_defaults(run=_agents)
    bench = commands.add_parser("bench", help="the speed figures beside their targets")
    _common(bench, "out/bench")
    bench.add_argument(
        "--seconds", type=float, default=60.0, help="simulated seconds per camera case (60)"
    )
    bench.add_argument(
        "--vector-steps",
        type=int,
        default=1000,
        help="vector-env steps per worker count (AsyncVectorEnv, SubprocVecEnv; rendered, fast)",
    )
    bench.add_argument(
        "--step-only", action="store_true", help="only the step section (env steps/s)"
    )
    bench.add_argument(
        "--steps", type=int, default=1500, help="timed env steps per step case (1500)"
    )
    bench.add_argument(
        "--rounds",
        type=int,
        default=5,
        help="fresh processes per step case and side, the best kept (5)",
    )
    bench.add_argument(
        "--baseline",
        type=Path,
        help="another checkout's folder or a Python with another stsf-gym installed: the step "
        "section runs on it too, side by side, with the ratio",
    )
    bench.set_defaults(run=_bench)
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


def _preflight(args: argparse.Namespace) -> None:
    """Every command's checks before any work: the seed, the option combinations of
    :data:`NEEDS` and :data:`EXCLUDES`, and ``--out`` (a folder, or the file a command writes);
    then temporary files a killed run left in ``--out`` are removed."""

    def given(option: str) -> bool:
        return getattr(args, option, None) is not None

    if getattr(args, "seed", 0) < 0:  # seeds seed a numpy SeedSequence: non-negative
        raise ConfigError(f"--seed must be at least 0, got {args.seed}")
    if getattr(args, "config", None) is not None:
        from stsf_gym.yaml_layers import read_yaml

        if not read_yaml(args.config):  # missing, unreadable or malformed: named there
            raise ConfigError(
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


def main(argv: list[str] | None = None) -> int:
    """Run a command. Bad input (a :class:`ConfigError`, :class:`FieldError` or a missing or
    unwritable path): a one-line error and exit code 2, before any output is written; jobs that
    failed twice: exit code 1 (finished results kept, a rerun resumes). Any other exception is
    a bug: it propagates with its traceback (exit code 1)."""
    from stsf_gym.experiments.cache import JobsFailed

    args = build_parser().parse_args(argv)
    set_command(["stsf-gym", *(sys.argv[1:] if argv is None else argv)])
    error = f"stsf-gym {args.command}: error:"
    try:
        _preflight(args)
        if args.verbose:
            from stsf_gym.envs.quiet import VERBOSE_ENV

            os.environ[VERBOSE_ENV] = "1"  # worker processes inherit it
        else:
            _silence_c_stdout()
        result = args.run(args)
    except (
        ConfigError,
        FieldError,
        FileNotFoundError,
        NotADirectoryError,
        IsADirectoryError,
        PermissionError,
    ) as err:
        print(f"{error} {err}", file=sys.stderr)
        return 2
    except (JobsFailed, NothingFinished) as err:
        print(f"{error} {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{error} interrupted; rerun with the same --out to resume", file=sys.stderr)
        return 130
    if args.json:
        print(json.dumps(result, default=lambda v: v.tolist() if hasattr(v, "tolist") else str(v)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
