"""Tables for the terminal: as many columns as the console is wide (80 when it is not a
terminal), never a number broken across lines; the other columns are in the files. A column of
names (agents, pose sources such as ``my_package.estimators:MyEstimator``) is at most
:data:`NAME_WIDTH` wide, its long names wrapped onto several lines, so one long name does not
push the numbers beside it off the screen. A cell listing several figures (``a; b; c``, one
per training run) is broken at its ``; `` when the table would not fit otherwise, one figure a
line, before any column is left out. This holds on a pipe or in a log as on a terminal.

:func:`print_markdown` prints a Markdown report (``results.md``) with each of its tables
fitted that way; :func:`fit_table` fits rows of values.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from rich import box
from rich.cells import cell_len
from rich.console import Console
from rich.table import Table

NAME_WIDTH = 20  # characters of a column of names; longer names wrap
_NUMBER = re.compile(r"[-+±]?\.?\d")  # a cell starting like a number is never wrapped
LIST = "; "  # between the figures of a cell that lists several


def _cell(value) -> str:
    return f"{value:.3f}" if isinstance(value, float) else str(value)


def _wrapped_name(name: str, width: int = NAME_WIDTH) -> str:
    """``name`` in lines of at most ``width``, broken after a ``:``, ``.``, ``/`` or ``-``
    where there is one (``my_package.`` / ``estimators:`` / ``MyEstimator``)."""
    lines = []
    while len(name) > width:
        cut = max(name.rfind(mark, 1, width) for mark in ":./-") + 1 or width
        lines.append(name[:cut])
        name = name[cut:]
    return "\n".join([*lines, name])


def _names_only(column: list[str]) -> bool:
    """True for a column of names: no cell of it starts like a number."""
    return not any(_NUMBER.match(cell) for cell in column)


def fit_table(
    header: Sequence[str],
    rows: Sequence[Sequence],
    width: int,
    title: str | None = None,
    rest_in: str | None = None,
) -> Table:
    """A rich table of ``rows`` with the leading columns that fit in ``width`` characters.

    The first column always stays; headers may wrap onto several lines, and so may the
    cells of a column of names (at :data:`NAME_WIDTH`); numbers never do. When columns are
    left out, the caption names them and ``rest_in`` (where they are).
    """
    cells = [[_cell(v) for v in row] for row in rows]
    widths, listed = [], []
    for i, name in enumerate(header):
        column = [row[i] for row in cells]
        header_width = max([cell_len(w) for w in name.split()] + [1])
        widest = max([cell_len(cell) for cell in column] + [header_width])
        if _names_only(column):
            widest = min(widest, max(NAME_WIDTH, header_width))
            for row in cells:
                row[i] = "\n".join(_wrapped_name(line, widest) for line in row[i].split("\n"))
        widths.append(widest)
        parts = [cell_len(part) + 1 for cell in column for part in cell.split(LIST)]
        listed.append(max([*parts, header_width]) if any(LIST in c for c in column) else widest)

    def fits(keep: int) -> bool:  # the columns, and 3 characters between two
        return sum(widths[:keep]) + 3 * (keep - 1) <= width

    for i in sorted(range(len(header)), key=lambda i: listed[i] - widths[i]):
        if fits(len(header)):
            break
        if listed[i] < widths[i]:  # one figure of the list a line
            widths[i] = listed[i]
            for row in cells:
                row[i] = row[i].replace(LIST, ";\n")
    keep = len(header)
    while keep > 1 and not fits(keep):
        keep -= 1
    table = Table(
        title=title, box=box.SIMPLE_HEAD, show_edge=False, pad_edge=False, title_justify="left"
    )
    for name, column_width in zip(header[:keep], widths, strict=False):
        table.add_column(name, width=column_width, overflow="fold")
    for row in cells:
        table.add_row(*row[:keep])
    left_out = header[keep:]
    if left_out:
        where = f" (in {rest_in})" if rest_in else ""
        table.caption = f"{len(left_out)} more column(s){where}: {', '.join(left_out)}"
        table.caption_justify = "left"
    return table


def _markdown_table(lines: list[str]) -> tuple[list[str], list[list[str]]]:
    split = [[c.strip() for c in line.strip().strip("|").split("|")] for line in lines]
    body = [r for r in split[1:] if not all(set(c) <= set("-: ") for c in r)]
    return split[0], body


def print_markdown(text: str, console: Console, rest_in: str | None = None) -> None:
    """Print a Markdown report: prose as it is, each table fitted to the console's width."""
    block: list[str] = []

    def flush_table() -> None:
        if block:
            header, rows = _markdown_table(block)
            console.print(fit_table(header, rows, console.width, rest_in=rest_in))
            block.clear()

    for line in text.splitlines():
        if line.lstrip().startswith("|"):
            block.append(line)
            continue
        flush_table()
        console.print(line, markup=False, highlight=False)
    flush_table()
