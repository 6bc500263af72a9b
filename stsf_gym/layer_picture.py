"""The picture of the import layers: rooms on floors, drawn as SVG from the import graph.

A *room* is a layer of :data:`stsf_gym.layers.ALLOWED` (a folder or a module, with the modules
it holds); its *floor* is its height in the graph: a room imports only rooms on lower floors,
or, inside a group of rooms that import one another (the simulator's ``envs``, ``worlds`` and
``rendering``), rooms of its own floor. An arrow is an import that no longer path of arrows
already implies (the graph's transitive reduction): ``python -m stsf_gym.layers`` lists every
import. The drawing is plain text built here, the same bytes on every machine, so
``tests/package/test_layers.py`` can hold the committed picture to what the code draws now.
"""

from __future__ import annotations

from collections.abc import Mapping
from xml.sax.saxutils import escape

ROW_ROOMS = 6  # rooms side by side at most; a fuller floor takes several rows
BOX_W, BOX_H, GAP_X = 168, 38, 18  # px
ROW_GAP, FLOOR_GAP, MARGIN, LABEL_W, TITLE_H = 34, 58, 14, 64, 54  # px
#: Fill of a room by the repository folder it lives in (a third-party room: none).
FILLS = {
    "stsf_gym": "#dbe8fb",
    "envs": "#dcf1dc",
    "agents": "#fde7cf",
    "configs": "#efe3f7",
    "": "#f2f2f2",
}
TITLE = (
    "Rooms are the layers of stsf_gym/layers.py; a room imports only rooms on lower floors (or, "
    "in a group such as envs, worlds and rendering, each other). An arrow is an import that no "
    "chain of other arrows implies: python -m stsf_gym.layers lists every import. Drawn from the "
    "code by python -m stsf_gym.layers --picture."
)


def groups(graph: Mapping[str, set[str]]) -> dict[str, frozenset[str]]:
    """Each room's group: the rooms it imports and is imported by, through any path."""
    reach = {room: _reach(graph, room) for room in graph}
    found = {}
    for room in graph:
        mutual = {other for other in reach[room] if room in reach[other]}
        found[room] = frozenset({room, *mutual})
    return found


def floors(graph: Mapping[str, set[str]]) -> dict[str, int]:
    """Each room's floor: 0 for a group importing no other group, else one above the highest
    group it imports."""
    group, found = groups(graph), {}

    def floor(room: str) -> int:
        if room not in found:
            below = {t for member in group[room] for t in graph[member]} - group[room]
            height = 1 + max((floor(t) for t in below), default=-1)
            found.update(dict.fromkeys(group[room], height))
        return found[room]

    for room in sorted(graph):
        floor(room)
    return found


def reduction(graph: Mapping[str, set[str]]) -> dict[str, set[str]]:
    """The arrows drawn: each import that no path through another room implies (a group's
    imports among themselves are all kept)."""
    group = groups(graph)
    kept = {}
    for room, targets in graph.items():
        implied = set()
        for other in targets - group[room]:
            implied |= _reach(graph, other)
        kept[room] = {t for t in targets if t in group[room] or t not in implied}
    return kept


def _reach(graph: Mapping[str, set[str]], room: str) -> set[str]:
    """The rooms ``room`` imports through any path (itself only through a cycle)."""
    seen: set[str] = set()
    todo = sorted(graph[room])
    while todo:
        target = todo.pop()
        if target not in seen:
            seen.add(target)
            todo += sorted(graph.get(target, ()))
    return seen


def rows(graph: Mapping[str, set[str]]) -> list[list[str]]:
    """The rooms in drawing rows, top floor first; inside a floor in the order that keeps
    arrows short (each room under the mean place of the rooms importing it), ties by name."""
    level = floors(graph)
    top = max(level.values())
    top_down = [sorted(r for r in graph if level[r] == f) for f in range(top, -1, -1)]
    place = {room: i for floor in top_down for i, room in enumerate(floor)}
    importers = {
        room: [source for source in graph if room in graph[source] and level[source] > level[room]]
        for room in graph
    }
    for floor in top_down[1:]:
        mean = {r: sum(place[s] for s in importers[r]) / max(1, len(importers[r])) for r in floor}
        floor.sort(key=lambda room: (mean[room] if importers[room] else len(floor), room))
        place.update({room: i for i, room in enumerate(floor)})
    return [floor[i : i + ROW_ROOMS] for floor in top_down for i in range(0, len(floor), ROW_ROOMS)]


def svg(
    graph: Mapping[str, set[str]],
    modules: Mapping[str, int],
    folders: Mapping[str, str],
) -> str:
    """The picture of ``graph`` (room -> rooms it imports) as an SVG document: ``modules``
    gives each room's module count, ``folders`` its repository folder (a fill colour)."""
    level, arrows = floors(graph), reduction(graph)
    drawn = rows(graph)
    width = 2 * MARGIN + LABEL_W + ROW_ROOMS * (BOX_W + GAP_X)
    boxes, y, bands, last = {}, TITLE_H, [], None
    for row in drawn:
        if last is not None:
            y += FLOOR_GAP if level[row[0]] != last else ROW_GAP
        if level[row[0]] != last:
            bands.append([level[row[0]], y, y])
        bands[-1][2] = y + BOX_H
        x0 = MARGIN + LABEL_W + (ROW_ROOMS - len(row)) * (BOX_W + GAP_X) // 2
        for i, room in enumerate(row):
            boxes[room] = (x0 + i * (BOX_W + GAP_X), y)
        last = level[row[0]]
    height = y + BOX_H + MARGIN + 10
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {width} {height}" '
        f'width="{width}" height="{height}" font-family="sans-serif" font-size="12">',
        '<defs><marker id="head" viewBox="0 0 8 8" refX="8" refY="4" markerWidth="7" '
        'markerHeight="7" orient="auto-start-reverse"><path d="M0,0 L8,4 L0,8 z" '
        'fill="#555"/></marker></defs>',
        f'<rect width="{width}" height="{height}" fill="white"/>',
        *_title(width),
    ]
    for floor, top, bottom in bands:
        out.append(
            f'<rect x="{MARGIN}" y="{top - 8}" width="{width - 2 * MARGIN}" '
            f'height="{bottom - top + 16}" rx="6" fill="#f7f7f9" stroke="#ddd"/>'
        )
        out.append(
            f'<text x="{MARGIN + 8}" y="{(top + bottom) // 2 + 4}" fill="#777">floor {floor}</text>'
        )
    out += _arrows(arrows, boxes)
    for room, (x, y) in boxes.items():
        out += _box(room, x, y, modules.get(room, 0), folders.get(room, ""))
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _title(width: int) -> list[str]:
    words, lines = TITLE.split(), [""]
    for word in words:  # about 7 px a character at 12 px
        if len(lines[-1]) + len(word) + 1 > (width - 2 * MARGIN) // 7:
            lines.append("")
        lines[-1] = f"{lines[-1]} {word}".strip()
    return [
        f'<text x="{MARGIN}" y="{18 + 16 * i}" fill="#333">{escape(line)}</text>'
        for i, line in enumerate(lines)
    ]


def _arrows(arrows: Mapping[str, set[str]], boxes: Mapping[str, tuple[int, int]]) -> list[str]:
    """The arrows, each from the bottom of its importer to the top of the room it imports, the
    ends spread along each box's edge in the order of the other ends; two rooms of one row
    importing each other: one arc below them, a head at each end."""
    pairs = sorted((s, t) for s in arrows for t in arrows[s] if boxes[s][1] != boxes[t][1])
    leaving = _ports(pairs, boxes, 0)
    arriving = _ports(pairs, boxes, 1)
    out = []
    for source, target in pairs:
        (a, top), (b, bottom) = leaving[source, target], arriving[source, target]
        bend = max(18, (bottom - top) // 3)
        out.append(
            f'<path d="M{a},{top} C{a},{top + bend} {b},{bottom - bend} {b},{bottom}" '
            'fill="none" stroke="#555" stroke-opacity="0.7" marker-end="url(#head)"/>'
        )
    level = sorted((s, t) for s in arrows for t in arrows[s] if boxes[s][1] == boxes[t][1])
    for source, target in level:
        both = source in arrows[target]
        if both and (target, source) < (source, target):
            continue  # drawn once, with a head at each end
        (x1, y1), (x2, _) = boxes[source], boxes[target]
        a, b, low = x1 + BOX_W // 2, x2 + BOX_W // 2, y1 + BOX_H + 16
        start = ' marker-start="url(#head)"' if both else ""
        out.append(
            f'<path d="M{a},{y1 + BOX_H} C{a},{low} {b},{low} {b},{y1 + BOX_H}" '
            f'fill="none" stroke="#555"{start} marker-end="url(#head)"/>'
        )
    return out


def _ports(
    pairs: list[tuple[str, str]], boxes: Mapping[str, tuple[int, int]], end: int
) -> dict[tuple[str, str], tuple[int, int]]:
    """Where each arrow of ``pairs`` meets its importer (``end`` 0: the box's bottom) or the
    room imported (1: its top): spread over the middle of the edge, ordered by the other end's
    place."""
    found = {}
    for room in sorted({pair[end] for pair in pairs}):
        mine = sorted((p for p in pairs if p[end] == room), key=lambda p: (boxes[p[1 - end]], p))
        x, y = boxes[room]
        for i, pair in enumerate(mine):
            offset = BOX_W * (1 + 2 * i) // (2 * len(mine))  # the i-th of len(mine) slots
            found[pair] = (x + BOX_W // 6 + offset * 2 // 3, y + (BOX_H if end == 0 else 0))
    return found


def _box(room: str, x: int, y: int, modules: int, folder: str) -> list[str]:
    label = room.removeprefix("stsf_gym.") if room != "stsf_gym" else "stsf_gym (__init__)"
    note = f"{modules} module{'s' * (modules != 1)}" if modules else "third party"
    dash = "" if folder else ' stroke-dasharray="4 3"'
    return [
        f'<rect x="{x}" y="{y}" width="{BOX_W}" height="{BOX_H}" rx="5" '
        f'fill="{FILLS.get(folder, FILLS[""])}" stroke="#667"{dash}/>',
        f'<text x="{x + BOX_W // 2}" y="{y + 16}" text-anchor="middle">{escape(label)}</text>',
        f'<text x="{x + BOX_W // 2}" y="{y + 31}" text-anchor="middle" font-size="10" '
        f'fill="#666">{note}</text>',
    ]
