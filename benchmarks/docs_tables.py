"""Tables of the docs generated from the registries, so they cannot go stale: the registered ids
and the shipped agents.

A generated table lies between ``<!-- generated: NAME (begin) -->`` and
``<!-- generated: NAME (end) -->`` in a page of :data:`BLOCKS`; ``tests/docs/test_docs_tables.py``
checks each equals what :data:`TABLES` makes of the registry now.

Usage::

    python benchmarks/docs_tables.py           # list the stale tables; exit 1 when one is
    python benchmarks/docs_tables.py --write   # rewrite them
"""

from __future__ import annotations

import re
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: How each algo of a shipped agent was trained, in words.
TRAINED = {
    "dagger": "cloned from the follower's demonstrations, then DAgger rounds; no reward",
    "dagger+ppo": "the DAgger clone, then PPO on the env's reward",
    "ppo": "PPO on the env's reward alone",
}


def _family(env_id: str) -> tuple[str, str | None]:
    """``stsf_gym/Suite-Sparse-MCL-v0`` -> ``("Suite-Sparse", "MCL")``; a raw env's source None."""
    from stsf_gym import ESTIMATOR_IDS

    name = env_id.removeprefix("stsf_gym/").removesuffix("-v0")
    for suffix in sorted(ESTIMATOR_IDS, key=len, reverse=True):
        if name.endswith(f"-{suffix}"):
            return name.removesuffix(f"-{suffix}"), suffix
    return name, None


def id_table() -> str:
    """Every registered id: a row per world (the raw env, then one id per pose source)."""
    import gymnasium as gym

    import stsf_gym  # noqa: F401  (registers the ids)

    rows: dict[str, list[str]] = {}
    for env_id in gym.registry:
        if env_id.startswith("stsf_gym/"):
            family, source = _family(env_id)
            rows.setdefault(family, []).append(f"`{source}`" if source else f"`{env_id}`")
    lines = ["| world | raw env | with a pose source: `stsf_gym/<world>-<source>-v0` |"]
    lines.append("| --- | --- | --- |")
    for family, ids in rows.items():
        raw = [i for i in ids if i.startswith("`stsf_gym/")]
        lines.append(
            f"| {family} | {', '.join(raw) or '-'} | {', '.join(i for i in ids if i not in raw)} |"
        )
    total = sum(len(ids) for ids in rows.values())
    return "\n".join(lines) + f"\n\n{total} ids in all.\n"


def agents_table() -> str:
    """Every shipped agent: its name and aliases, how it was trained, on what, and the
    validation success of each seed (``stsf-gym agents --json``)."""
    from stsf_gym.agents import pretrained

    lines = ["| shipped agent (aliases) | how it was trained | trained on | val success per seed |"]
    lines.append("| --- | --- | --- | --- |")
    for agent in pretrained.listing():
        aliases = ", ".join(f"`{a.removeprefix(pretrained.PREFIX)}`" for a in agent["aliases"])
        name = f"`{agent['name']}`" + (f" ({aliases})" if aliases else "")
        success = ", ".join(f"{v:.2f}" for v in agent["val_success"].values())
        source = f"{agent['pose_source']}, {agent['suite']} suite"
        lines.append(
            f"| {name} | {TRAINED.get(agent['algo'], agent['algo'])} | {source} | {success} |"
        )
    return "\n".join(lines) + "\n"


#: Each generated table by name, and how it is made.
TABLES: dict[str, Callable[[], str]] = {"ids": id_table, "shipped agents": agents_table}
#: Where each table is generated: page, table name.
BLOCKS = [
    ("docs/benchmark/index.md", "ids"),
    ("docs/getting-started.md", "ids"),
    ("docs/agents.md", "shipped agents"),
]


def _pattern(name: str) -> re.Pattern:
    return re.compile(
        rf"(<!-- generated: {re.escape(name)} \(begin\) -->\n)(.*?)(<!-- generated: "
        rf"{re.escape(name)} \(end\) -->)",
        re.S,
    )


def stale(root: Path = ROOT) -> list[str]:
    """The blocks whose text is not the table generated now (or that are missing)."""
    found = []
    for page, name in BLOCKS:
        match = _pattern(name).search((root / page).read_text())
        if match is None or match.group(2) != TABLES[name]():
            found.append(f"{page}: {name}")
    return found


def write(root: Path = ROOT) -> None:
    """Rewrite every block with the table generated now."""
    for page, name in BLOCKS:
        path, table = root / page, TABLES[name]()
        text = _pattern(name).sub(lambda m, t=table: m.group(1) + t + m.group(3), path.read_text())
        path.write_text(text)


if __name__ == "__main__":
    if "--write" in sys.argv[1:]:
        write()
    listed = stale()
    print("\n".join(f"stale: {block}" for block in listed) or "every generated table is current")
    sys.exit(1 if listed else 0)
