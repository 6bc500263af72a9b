"""Measured blocks of README.md and docs/: which quote results made by the code as it is now.

A measured block lies between ``<!-- measured: NAME (begin) -->`` and
``<!-- measured: NAME (end) -->``. A block is **tied** when its begin marker names the results
files it quotes, ``<!-- measured: NAME (begin) results: PATH, PATH -->`` (repository paths), each
with its ``provenance`` (``command``, ``stsf_gym.source_digest``, ``stsf_gym.commit``), and its
text shows each file's command and code digest. A tied block is **current** when the code each
of its files was made with is unchanged, else **stale**: its results were made by code that has
changed since. A file that lists the code its run loaded (``stsf_gym.loaded_code``: each module
imported by the run or its workers, and every config, with its digest,
:func:`stsf_gym.results.provenance.loaded_code`) is unchanged when every listed file's bytes
now have the same digest (a file deleted since counts as changed), so an edit to code the run
never loaded leaves it current; a stale block's note names the changed files. A file without
that list (made before it was recorded) is unchanged only when its ``source_digest`` is the
digest of all the code now (:func:`stsf_gym.results.provenance.source_digest`: every module and
config of stsf_gym/, envs/, agents/ and configs/). A shipped agent a command names
(``pretrained:<suite>/<agent>``) is code too: its model files are in the run's list, and a run
that did not list them (made before runs did) is stale. A block that names no results is **not
tied**; it must be listed in ``benchmarks/measured_not_tied.yaml`` with the reason, so the list
stays visible.

Rules (``tests/test_measured_blocks.py`` runs them in ``make test``): markers pair up and names
are unique; a tied block's files exist, carry provenance and are shown in its text; an untied
block is listed with a reason, and the list names no other block; README.md's blocks are
current (the README quotes no stale figure).

A rewrite that gives the same numbers to the bit (the step's hot path compiled, say) changes a
file's bytes, not what a run computes. ``benchmarks/equivalent_code.yaml`` records each such
rewrite: the file, its digest before and after, the commit before it, and the tests that prove the
equality (they must exist and run in ``make test``). A loaded file whose digest reaches its
current one through a chain of these records counts as unchanged, except for timings
(results of ``stsf-gym bench``): a rewrite is made to change those. A record's optional
``changes`` names other commands whose results it does change (``[stsf-gym train]`` for a
setting only training reads): for their results the file has changed.

Usage::

    python benchmarks/measured_blocks.py [--json]    # every block; exit 1 when a rule is broken
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import subprocess
import sys
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import yaml

from stsf_gym.agents.pretrained import MODELS, PREFIX
from stsf_gym.results.provenance import file_digest, source_digest

ROOT = Path(__file__).resolve().parent.parent
NOT_TIED = Path("benchmarks/measured_not_tied.yaml")  # relative to the repository
EQUIVALENT = Path("benchmarks/equivalent_code.yaml")  # bit-exact rewrites, relative too
#: The command whose results are timings, which every equivalent rewrite is made to change.
TIMINGS = "stsf-gym bench"
#: The Markdown files searched: the README and every page of the site.
PAGES = ("README.md", "docs")
#: The folders whose code the digest covers (pyproject's package-dir).
CODE = ("stsf_gym", "envs", "agents", "configs")
NAMED = 3  # changed files a note names before "and N more"
#: A shipped agent named in a command (``pretrained:<suite>/<agent>``), and its models' folder.
SHIPPED = re.compile(re.escape(PREFIX) + r"(?P<name>[\w.-]+/[\w.-]+)")
SHIPPED_MODELS = MODELS.relative_to(ROOT).as_posix() + "/{name}/"
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


def _git(*args: str, root: Path) -> str | None:
    done = subprocess.run(["git", *args], cwd=root, capture_output=True, text=True)
    return done.stdout.strip() if done.returncode == 0 else None


def changes_since(commit: str | None, root: Path = ROOT, files: Sequence[str] = ()) -> str:
    """How ``files`` (default: all the measured code) have changed since ``commit``, in words."""
    if not commit:
        return "the run recorded no commit (its code was no git checkout)"
    count = _git("rev-list", "--count", f"{commit}..HEAD", "--", *(files or CODE), root=root)
    if count is None:
        return f"commit {commit[:10]} is not in this repository's history"
    what = "them" if files else "the code"
    return f"made at commit {commit[:10]}; {count} later commits changed {what}"


Rewrites = Mapping[tuple[str, str], tuple[str, tuple[str, ...]]]


def equivalent_rewrites(root: Path = ROOT) -> tuple[Rewrites, list[str]]:
    """``{(path, digest before): (digest after, commands it changes)}`` of the bit-exact
    rewrites recorded in :data:`EQUIVALENT` (every one changes :data:`TIMINGS`), and the
    problems of the record (a missing key, a proof that is no test file of the repository)."""
    record = root / EQUIVALENT
    entries = yaml.safe_load(record.read_text()) if record.is_file() else None
    rewrites, problems = {}, []
    for number, entry in enumerate(entries or [], 1):
        missing = [
            k for k in ("path", "before", "after", "before_commit", "proof") if k not in entry
        ]
        if missing:
            problems.append(f"{EQUIVALENT}: rewrite {number} lacks {', '.join(missing)}")
            continue
        for proof in entry["proof"]:
            if not (proof.startswith("tests/") and (root / proof).is_file()):
                problems.append(f"{EQUIVALENT}: rewrite {number}'s proof {proof} is no test file")
        changes = (TIMINGS, *entry.get("changes", []))
        rewrites[(entry["path"], entry["before"])] = (entry["after"], changes)
    return rewrites, problems


def applying(rewrites: Rewrites, command: str) -> dict[tuple[str, str], str]:
    """``{(path, digest before): digest after}`` of the ``rewrites`` that leave the results of
    ``command`` unchanged (those that name no prefix of it in their ``changes``)."""
    words = command.split()
    return {
        key: after
        for key, (after, changes) in rewrites.items()
        if not any(words[: len(c.split())] == c.split() for c in changes)
    }


def _same_code(path: str, digest: str, now: str, rewrites: Mapping[tuple[str, str], str]) -> bool:
    """Whether ``path`` at ``digest`` reaches ``now`` through bit-exact rewrites (or is it)."""
    seen = set()
    while digest != now and digest not in seen:
        seen.add(digest)
        digest = rewrites.get((path, digest), digest)
    return digest == now


def changed_files(
    loaded: Mapping[str, str],
    root: Path = ROOT,
    rewrites: Mapping[tuple[str, str], str] | None = None,
) -> list[str]:
    """The files of ``loaded`` (``{repository path: digest}``) whose bytes under ``root`` have
    another digest now that no chain of ``rewrites`` leads to, or that are gone."""
    return [
        path
        for path, digest in sorted(loaded.items())
        if not (root / path).is_file()
        or not _same_code(path, digest, file_digest(root / path), rewrites or {})
    ]


def _named(files: list[str]) -> str:
    more = f" and {len(files) - NAMED} more" if len(files) > NAMED else ""
    return ", ".join(files[:NAMED]) + more


def unrecorded_agents(command: str, loaded: Mapping[str, str] | None) -> list[str]:
    """The shipped agents ``command`` names whose model files ``loaded`` does not list (a run
    made before it recorded them): whether the agent shipped now made its results is unknown."""
    names = dict.fromkeys(match["name"] for match in SHIPPED.finditer(command))
    return [
        PREFIX + name
        for name in names
        if not any(path.startswith(SHIPPED_MODELS.format(name=name)) for path in loaded or {})
    ]


def staleness(
    code: Mapping[str, Any],
    digest: str,
    root: Path = ROOT,
    rewrites: Mapping[tuple[str, str], str] | None = None,
    command: str = "",
) -> str | None:
    """Why the code a results file was made with (its provenance's ``stsf_gym``) has changed,
    or None when it has not: by the files its run loaded (``rewrites`` leave a file the same),
    else (an older file) by the digest. A shipped agent ``command`` names counts as code: a
    run that did not record its models' digests is stale."""
    loaded, commit = code.get("loaded_code"), code.get("commit")
    unrecorded = unrecorded_agents(command, loaded)
    if unrecorded:
        return (
            f"it ran {_named(unrecorded)} without recording the models' digests (made before "
            f"runs recorded them), so the agents shipped now may not be the ones it measured"
        )
    if loaded is not None:
        changed = changed_files(loaded, root, rewrites)
        if not changed:
            return None
        return (
            f"{len(changed)} of the {len(loaded)} files its run loaded changed "
            f"({_named(changed)}), {changes_since(commit, root, changed)}"
        )
    if code["source_digest"] == digest:
        return None
    return f"digest {code['source_digest']}, {changes_since(commit, root)}"


def judge(
    block: Block,
    digest: str,
    root: Path = ROOT,
    rewrites: Rewrites | None = None,
) -> list[str]:
    """Set ``block.state`` and ``block.notes``; return the rules it breaks. ``rewrites``
    (:func:`equivalent_rewrites`) apply to the results of every command they do not change."""
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
        rewritten = applying(rewrites or {}, made_by["command"])
        why = staleness(code, digest, root, rewritten, made_by["command"])
        if why is not None:
            stale = True
            block.notes.append(f"{name}: {why}")
    if block.results:
        block.state = "stale" if stale else "current"
    return problems


def check(root: Path = ROOT, digest: str | None = None) -> tuple[list[Block], list[str]]:
    """Every block judged against the code under ``root`` (files without a list of the code
    they loaded: against ``digest``, default the package's now), and the problems: broken rules
    (see the module's docstring)."""
    digest = digest or source_digest()
    blocks, problems = find_blocks(root)
    rewrites, record_problems = equivalent_rewrites(root)
    problems += record_problems
    not_tied = yaml.safe_load((root / NOT_TIED).read_text()) or {}
    for block in blocks:
        problems += judge(block, digest, root, rewrites)
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


def record_rewrite(
    paths: Sequence[str],
    what: str,
    proof: Sequence[str],
    root: Path = ROOT,
    changes: Sequence[str] = (),
):
    """Append to :data:`EQUIVALENT` the rewrite of each of ``paths`` from its bytes at git's
    ``HEAD`` to its bytes now (uncommitted), with ``what`` changed, the ``proof`` tests and
    the commands whose results it ``changes`` (besides timings)."""
    commit = _git("rev-parse", "--short", "HEAD", root=root)
    problems = [f"{t}: no test file" for t in proof if not (root / t).is_file()]
    if commit is None or not proof or problems:
        raise SystemExit(f"cannot record: {problems or 'no commit or no proof'}")
    lines = []
    for path in paths:
        before = subprocess.run(["git", "show", f"HEAD:{path}"], cwd=root, capture_output=True)
        if before.returncode or not (root / path).is_file():
            raise SystemExit(f"cannot record {path}: not in HEAD or not here")
        lines += [
            f"- path: {path}",
            f"  before: {hashlib.sha256(before.stdout).hexdigest()[:16]}",  # as file_digest
            f"  after: {file_digest(root / path)}",
            f"  before_commit: {commit}",
            f"  what: {json.dumps(what)}",
            f"  proof: [{', '.join(proof)}]",
            *([f"  changes: [{', '.join(changes)}]"] if changes else []),
        ]
    with (root / EQUIVALENT).open("a") as record:
        record.write("\n".join(lines) + "\n")


def main(argv: list[str] | None = None) -> int:
    """List every measured block; exit 1 when a rule is broken. With ``--rewrite``, record a
    bit-exact rewrite instead."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print the blocks as JSON")
    parser.add_argument(
        "--rewrite",
        nargs="+",
        metavar="PATH",
        help="record these files' uncommitted change as a bit-exact rewrite (with --what, --proof)",
    )
    parser.add_argument("--what", default="", help="what the rewrite changed")
    parser.add_argument("--proof", nargs="+", default=[], help="the tests that prove it")
    parser.add_argument(
        "--changes", nargs="+", default=[], help="commands whose results it does change"
    )
    args = parser.parse_args(argv)
    if args.rewrite:
        record_rewrite(args.rewrite, args.what, args.proof, changes=args.changes)
        return 0
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
