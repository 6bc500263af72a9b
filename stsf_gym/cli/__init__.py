"""The ``stsf-gym`` command line. Every command takes ``--seed``, ``--out``, ``--config``,
``--set key=value``, ``--json`` (a machine-readable result on stdout) and ``--verbose``
(PyBullet's C banners, quiet by default)."""

from __future__ import annotations

import argparse
import difflib
import errno
import importlib
import json
import os
import sys

from stsf_gym.cli.options import preflight, refuse_unknown
from stsf_gym.cli.reports import NothingFinished
from stsf_gym.envs.quiet import VERBOSE_ENV
from stsf_gym.experiments.jobs.cache import JobsFailed
from stsf_gym.results.run_context import RunContext, run_context
from stsf_gym.validation import ConfigError, FieldError

#: Each command: its module in this package (its options and the handler that calls the API)
#: and its line in ``stsf-gym --help``, in the order listed there.
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("demo", "the follower on each estimator, IRL corridor"),
    "reproduce": ("reproduce", "the paper's experiments"),
    "evaluate": ("evaluate", "an agent on each estimator, many seeds"),
    "replay": ("replay", "pose sources rerun on recorded MCAP logs (no simulator)"),
    "train": ("train", "a learnt agent on one pose source"),
    "sweep": ("sweep", "a grid of evaluation or training cells"),
    "accuracy-curve": (
        "accuracy_curve",
        "success against localization error: how good must it be?",
    ),
    "benchmark": (
        "benchmark",
        "agents x pose sources on a suite's test worlds: the leaderboard",
    ),
    "world": (
        "world",
        "a generated world as world YAML (--seed N), or a grid of them (--grid)",
    ),
    "agents": ("agents", "the agents shipped trained (pretrained:...)"),
    "bench": ("bench", "the speed figures beside their targets"),
}


def build_parser(command: str | None) -> argparse.ArgumentParser:
    """The ``stsf-gym`` argument parser: every command listed, and the options of ``command``
    (only its module is imported, so ``stsf-gym --help`` and each command start fast); the
    command's own parser is its attribute ``command_parser`` (None without a command)."""
    parser = argparse.ArgumentParser(prog="stsf-gym", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    parser.command_parser = None  # type: ignore[attr-defined]
    for name, (module, help_line) in COMMANDS.items():
        sub = commands.add_parser(name, help=help_line)
        if name == command:
            handler = importlib.import_module(f"{__name__}.{module}")
            handler.add_arguments(sub)
            sub.set_defaults(run=handler.run)
            parser.command_parser = sub  # type: ignore[attr-defined]
    return parser


def _command(argv: list[str]) -> str | None:
    """The command named in ``argv``: its first word that is not an option."""
    return next((word for word in argv if not word.startswith("-")), None)


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
    """Run a command. Bad input (a :class:`ConfigError`, :class:`FieldError` or a missing or
    unwritable path): a one-line error and exit code 2, before any output is written; jobs that
    failed twice, or a full disk: exit code 1 (finished results kept, a rerun resumes). Any
    other exception is a bug: it propagates with its traceback (exit code 1)."""
    words = sys.argv[1:] if argv is None else list(argv)
    if "--verbose" in words:  # before the parser: building it loads PyBullet, banners and all
        os.environ[VERBOSE_ENV] = "1"  # worker processes inherit it
    command = _command(words)
    parser = build_parser(command)
    if command is not None and command not in COMMANDS:  # named with the command meant
        close = difflib.get_close_matches(command, COMMANDS, n=1, cutoff=0.6)
        hint = f" (did you mean {close[0]}?)" if close else ""
        parser.error(f"unknown command {command!r}{hint}; see stsf-gym --help")
    command_parser = getattr(parser, "command_parser", None)
    if command_parser is not None:  # an unknown option first: named with the one meant
        refuse_unknown(command_parser, words)
    args = parser.parse_args(words)
    error = f"stsf-gym {args.command}: error:"
    try:
        with run_context(RunContext.of(["stsf-gym", *words])):  # what its results record
            preflight(args)
            if not args.verbose:
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
    except OSError as err:
        if err.errno != errno.ENOSPC:
            raise
        where = f" writing {err.filename}" if err.filename else ""
        print(
            f"{error} the disk is full{where}; every file saved before stays valid (files "
            "are written whole or not at all): free space and rerun with the same --out to "
            "resume",
            file=sys.stderr,
        )
        return 1
    except KeyboardInterrupt:
        print(f"{error} interrupted; rerun with the same --out to resume", file=sys.stderr)
        return 130
    if args.json:
        print(json.dumps(result, default=lambda v: v.tolist() if hasattr(v, "tolist") else str(v)))
    return 0
