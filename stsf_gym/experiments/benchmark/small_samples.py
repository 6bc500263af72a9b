"""Intervals from too few worlds to separate anything, marked as such.

The rule: with ``n`` paired worlds, the strongest evidence two agents (or pose sources) can
give is every world going the same way. The sign test then has the two-sided p-value
``2 * 0.5 ** n``: 0.0625 at ``n = 5``, 0.031 at ``n = 6``. Below :data:`MIN_PAIRED_WORLDS`
no paired outcome at all is significant at 95 %, and a paired bootstrap over so few worlds
resamples so few distinct sets that agreement on every world gives a zero-width interval
(``+0.00 (+0.00 to +0.00)``) which only looks certain. Such an interval is printed with
:data:`MARK` and :func:`few_worlds_note` beside the table.
"""

from __future__ import annotations

MARK = "†"


def min_paired_worlds(alpha: float = 0.05) -> int:
    """The fewest paired worlds whose most one-sided outcome the two-sided sign test rejects
    at level ``alpha``: the smallest ``n`` with ``2 * 0.5 ** n < alpha``."""
    n = 1
    while 2 * 0.5**n >= alpha:
        n += 1
    return n


MIN_PAIRED_WORLDS = min_paired_worlds()  # 6


def too_few(worlds: int) -> bool:
    """Whether ``worlds`` paired worlds are too few to separate anything at 95 %."""
    return worlds < MIN_PAIRED_WORLDS


def marked(interval: str, worlds: int) -> str:
    """``interval`` as printed: with :data:`MARK` when it comes from too few worlds."""
    return f"{interval} {MARK}" if too_few(worlds) else interval


def interval(value: dict, worlds: int, digits: int = 2) -> str:
    """A paired difference ``{difference, low, high}`` over ``worlds`` worlds as printed:
    ``+0.10 (-0.05 to +0.25)``, :func:`marked`."""
    d, low, high = value["difference"], value["low"], value["high"]
    return marked(f"{d:+.{digits}f} ({low:+.{digits}f} to {high:+.{digits}f})", worlds)


def noted(table: str, worlds: int) -> str:
    """A Markdown ``table`` of paired intervals over ``worlds`` worlds, with the note under it
    when they are too few."""
    note = few_worlds_note(worlds)
    return f"{table}\n{note}\n" if note else table


def few_worlds_note(worlds: int) -> str | None:
    """The note printed under a table whose intervals come from ``worlds`` paired worlds
    (None when they are enough)."""
    if not too_few(worlds):
        return None
    return (
        f"{MARK} From {worlds} paired world(s): too few to separate anything. Even when every "
        f"world goes the same way, the sign test's p-value is 2 x 0.5^{worlds} = "
        f"{2 * 0.5**worlds:.3f}, above 0.05; it takes at least {MIN_PAIRED_WORLDS} worlds "
        "(--worlds) for any difference to be shown at 95 %."
    )
