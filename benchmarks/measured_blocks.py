"""Measured blocks of README.md and docs/: which quote results made by the code as it behaves now.

A measured block lies between ``<!-- measured: NAME (begin) -->`` and
``<!-- measured: NAME (end) -->``. A block is **tied** when its begin marker names the results
files it quotes, ``<!-- measured: NAME (begin) results: PATH, PATH -->`` (repository paths), each
with its ``provenance`` (``command``, ``stsf_gym.source_digest``, ``stsf_gym.behaviour``), and
its text shows each file's command and code digest. A tied block is **current** when every
file's numbers would come out the same from the code now, else **stale**. That is judged by
behaviour, not by bytes (:mod:`stsf_gym.results.behaviour`):

- each subsystem the run loaded must have the behaviour version it recorded (``behaviour``); a
  file that recorded none was made before versions were, and is stale;
- a shipped agent the command names (``pretrained:<suite>/<agent>``) must have the model files
  the run loaded, byte for byte (``loaded_code``): an agent shipped again is other data;
- timings (``stsf-gym bench``) depend on the code itself: every file the run loaded must compute
  what it computed then (``timed_code``: digests without docstrings and comments).

A block that names no results is **not tied**; it must be listed in
``benchmarks/measured_not_tied.yaml`` with the reason, so the list stays visible.

Rules (``tests/docs/test_measured_blocks.py`` runs them in ``make test``): markers pair up and names
are unique; a tied block's files exist, carry provenance and are shown in its text; an untied
block is listed with a reason, and the list names no other block; README.md's blocks are
current (the README quotes no stale figure).

Usage::

    python benchmarks/measured_blocks.py [--json]    # every block; exit 1 when a rule is broken
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import yaml

from stsf_gym.agents.pretrained import ALIASES, MODELS, PREFIX
from stsf_gym.results.behaviour import VERSIONS, code_digest
from stsf_gym.results.code_identity import file_digest

ROOT = Path(__file__).resolve().parent.parent
NOT_TIED = Path("benchmarks/measured_not_tied.yaml")  # relative to the repository
#: The command whose results are timings, which depend on the code itself.
TIMINGS = "stsf-gym bench"
#: The Markdown files searched: the README and every page of the site.
PAGES = ("README.md", "docs")
NAMED = 3  # changed files a note names before "and N more"
#: A shipped agent named in a command (``pretrained:<suite>/<agent>``), and its models' folder.
SHIPPED = re.compile(re.escape(PREFIX) + r"(?P<name>[\w.-]+/[\w.-]+)")
SHIPPED_ROOT = MODELS.relative_to(ROOT).as_posix() + "/"
SHIPPED_MODELS = SHIPPED_ROOT + "{name}/"
MARKER = re.compile(
    r"<!-- measured: (?P<name>.+?) \((?P<edge>begin|end)\)(?: results: (?P<results>[^>]*?))? -->"
)


@dataclass
class Block:
    """One measured block: where it is, what it quotes, and what the check found."""

    name: str
    page: str
    line: int
    results: list[str]
    text: str = field(repr=False)
    state: str = "not tied"  # "current", "stale" or "not tied"
    notes: list[str] = field(default_factory=list)


def markdown_files(root: Path = ROOT) -> list[Path]:
    """README.md and every Markdown page under docs/."""
    files = []
    for entry in PAGES:
        path = root / entry
        files += sorted(path.rglob("*.md")) if path.is_dir() else [path]
    return files


def find_blocks(root: Path = ROOT) -> tuple[list[Block], list[str]]:
    """Every measured block of the pages, and the marker problems found on the way."""
    blocks, problems = [], []
    for path in markdown_files(root):
        page = path.relative_to(root).as_posix()
        text = path.read_text()
        open_block: tuple[re.Match, int] | None = None
        for match in MARKER.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            where = f"{page}:{line}"
            if match["edge"] == "begin":
                if open_block is not None:
                    problems.append(f"{where}: {match['name']!r} begins inside another block")
                open_block = (match, line)
                continue
            if open_block is None or open_block[0]["name"] != match["name"]:
                problems.append(f"{where}: end of {match['name']!r} without its begin")
                open_block = None
                continue
            begin, begin_line = open_block
            results = [p.strip() for p in (begin["results"] or "").split(",") if p.strip()]
            body = text[begin.end() : match.start()]
            blocks.append(Block(begin["name"], page, begin_line, results, body))
            open_block = None
        if open_block is not None:
            problems.append(f"{page}:{open_block[1]}: {open_block[0]['name']!r} never ends")
    names = [block.name for block in blocks]
    problems += [
        f"block name {name!r} is used twice" for name in sorted(set(names)) if names.count(name) > 1
    ]
    return blocks, problems


def _named(files: list[str]) -> str:
    more = f" and {len(files) - NAMED} more" if len(files) > NAMED else ""
    return ", ".join(files[:NAMED]) + more


def moved_versions(recorded: Mapping[str, int]) -> list[str]:
    """The subsystems whose behaviour version is not the one ``recorded`` now."""
    return [
        f"{name} v{version} -> v{VERSIONS.get(name, 'gone')}"
        for name, version in sorted(recorded.items())
        if VERSIONS.get(name) != version
    ]


def unrecorded_agents(
    command: str, loaded: Mapping[str, str] | None, root: Path = ROOT
) -> list[str]:
    """The shipped agents ``command`` names whose model files ``loaded`` does not list (a run
    made before it recorded them): whether the agent shipped now made its results is unknown."""
    names = dict.fromkeys(match["name"] for match in SHIPPED.finditer(command))
    renamed = shipped_aliases(root)
    paths = [shipped_now(path, renamed) for path in loaded or {}]
    return [
        PREFIX + name
        for name in names
        if not any(
            path.startswith(SHIPPED_MODELS.format(name=renamed.get(name, name))) for path in paths
        )
    ]


def shipped_aliases(root: Path = ROOT) -> dict[str, str]:
    """``{<suite>/<old name>: <suite>/<name now>}`` of the shipped agents renamed under ``root``
    (``aliases.json`` beside them, :func:`stsf_gym.agents.pretrained.aliases`)."""
    record = root / SHIPPED_ROOT / ALIASES.name
    return json.loads(record.read_text()) if record.is_file() else {}


def shipped_now(path: str, renamed: Mapping[str, str]) -> str:
    """A shipped model's repository path under the name its agent is shipped under now: an agent
    renamed (its old name an alias, ``renamed``) keeps its models, byte for byte."""
    parts = path.removeprefix(SHIPPED_ROOT).split("/", 2)
    if not path.startswith(SHIPPED_ROOT) or len(parts) != 3:
        return path
    suite, agent, file = parts
    name = f"{suite}/{agent}"
    return SHIPPED_MODELS.format(name=renamed.get(name, name)) + file


def changed_files(digests: Mapping[str, str], digest_of, root: Path = ROOT) -> list[str]:
    """The files of ``digests`` (``{repository path: digest}``) that are gone or whose
    ``digest_of(path)`` is another now."""
    return [
        path
        for path, digest in sorted(digests.items())
        if not (root / path).is_file() or digest_of(root / path) != digest
    ]


def staleness(code: Mapping[str, Any], command: str, root: Path = ROOT) -> str | None:
    """Why the numbers of a results file made by ``code`` (its provenance's ``stsf_gym``) with
    ``command`` may differ now, or None when they would not (see the module's docstring)."""
    loaded = code.get("loaded_code") or {}
    unrecorded = unrecorded_agents(command, loaded, root)
    renamed = shipped_aliases(root)
    if unrecorded:
        return f"it ran {_named(unrecorded)} without recording the models' digests"
    models = {
        shipped_now(path, renamed): d for path, d in loaded.items() if path.startswith(SHIPPED_ROOT)
    }
    reshipped = changed_files(models, file_digest, root)
    if reshipped:
        return f"shipped again since: {_named(reshipped)}"
    if "behaviour" not in code:
        return "made before results recorded behaviour versions"
    moved = moved_versions(code["behaviour"])
    if moved:
        return f"behaviour changed: {', '.join(moved)}"
    if command.split()[:2] == TIMINGS.split():
        if "timed_code" not in code:
            return "timings made before results recorded the code they timed"
        changed = changed_files(code["timed_code"], code_digest, root)
        if changed:
            return f"timings of code that has changed: {_named(changed)}"
    return None


def judge(block: Block, root: Path = ROOT) -> list[str]:
    """Set ``block.state`` and ``block.notes``; return the rules it breaks."""
    problems = []
    where = f"{block.page}:{block.line} {block.name!r}"
    stale = False
    for name in block.results:
        path = root / name
        if not path.is_file():
            problems.append(f"{where}: results file {name} does not exist")
            continue
        made_by = json.loads(path.read_text()).get("provenance") or {}
        code = made_by.get("stsf_gym") or {}
        if not made_by.get("command") or not code.get("source_digest"):
            problems.append(f"{where}: {name} carries no provenance (command, source_digest)")
            continue
        for shown in (made_by["command"], code["source_digest"]):
            if shown not in block.text:
                problems.append(f"{where}: the block does not show {name}'s {shown!r}")
        why = staleness(code, made_by["command"], root)
        if why is not None:
            stale = True
            block.notes.append(f"{name}: {why}")
    if block.results:
        block.state = "stale" if stale else "current"
    return problems


def check(root: Path = ROOT) -> tuple[list[Block], list[str]]:
    """Every block judged against the code under ``root``, and the problems: broken rules
    (see the module's docstring)."""
    blocks, problems = find_blocks(root)
    not_tied = yaml.safe_load((root / NOT_TIED).read_text()) or {}
    for block in blocks:
        problems += judge(block, root)
        if block.results:
            if block.name in not_tied:
                problems.append(f"{block.name!r} is tied but listed in {NOT_TIED.name}")
        elif block.name in not_tied:
            block.notes.append(str(not_tied[block.name]))
        else:
            problems.append(
                f"{block.page}:{block.line} {block.name!r} names no results and "
                f"{NOT_TIED.name} gives no reason"
            )
        if block.page == "README.md" and block.state != "current":
            problems.append(f"README.md quotes {block.name!r}, which is {block.state}")
    known = {block.name for block in blocks}
    problems += [
        f"{NOT_TIED.name} lists {name!r}, which is no block"
        for name in not_tied
        if name not in known
    ]
    return blocks, problems


def listing(blocks: list[Block]) -> str:
    """One line per block (state, name, where), its notes indented below."""
    lines = []
    for block in blocks:
        lines.append(f"{block.state:9} {block.name} ({block.page}:{block.line})")
        lines += [f"          {note}" for note in block.notes]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """List every measured block; exit 1 when a rule is broken."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print the blocks as JSON")
    args = parser.parse_args(argv)
    blocks, problems = check()
    if args.json:
        rows = [{k: v for k, v in asdict(b).items() if k != "text"} for b in blocks]
        print(json.dumps({"blocks": rows, "problems": problems}, indent=2))
    else:
        print(listing(blocks))
        print("\n".join(f"problem: {p}" for p in problems))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
