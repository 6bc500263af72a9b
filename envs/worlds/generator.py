"""Corridor worlds drawn from a seed: the same :class:`~stsf_gym.envs.config.WorldConfig` a YAML
world gives, checked like one. Pure numpy, no PyBullet.

:func:`generate_world` draws, with ``numpy.random.default_rng(seed)`` only:

1. **the main path**: ``segments`` straight, axis-aligned legs from the start (the origin,
   heading east) with a left or right turn between legs (L, U and zig-zag shapes), each leg
   ``segment_length`` long and ``width`` wide (clear, wall face to wall face); legs that do not
   meet keep ``min_gap`` of wall between them; redrawn until the path is at least
   ``min_path_length`` long;
2. **dead-end side branches** (T junctions): perpendicular to a leg's middle, or straight on
   past a turn, ``branch_length`` long;
3. **walls**: the boundary of the legs' union (:mod:`stsf_gym.envs.worlds.layout`);
4. **clutter**: boxes and cylinders against the walls, each leaving ``robot.body_radius +
   path_clearance`` free around the path and ``corner_distance`` from turns, start and goal;
5. **landmarks**: candidates on every wall every ``candidate_step``; a greedy cover keeps
   those that make every path point see ``landmarks_in_view`` of them (at least one is a
   must: :mod:`stsf_gym.envs.worlds.visibility` defines *seen*).

A layout that fails a step is drawn again (up to ``attempts`` times). The world is returned as
the mapping a world YAML holds (:func:`world_tree`), so it can be written out and edited.
"""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.envs.config import EnvConfig, WorldConfig, build
from stsf_gym.envs.worlds.coverage import board_centres, coverage_of
from stsf_gym.envs.worlds.generator_config import GeneratorConfig
from stsf_gym.envs.worlds.layout import DIRECTIONS, Rect, boundary_walls
from stsf_gym.envs.worlds.spec import obstacle_distance
from stsf_gym.envs.worlds.visibility import (
    CameraView,
    choose_landmarks,
    path_samples,
    sample_arc_lengths,
    seen_matrix,
)
from stsf_gym.validation import ConfigError

CAP = 3  # decimals of every coordinate in a generated world (millimetres)


class GenerationError(ConfigError):
    """No valid world was found within ``attempts`` layouts: the generator's settings (bad
    input, named by the CLI like any other) leave too little room."""


def generate_world(seed: int, gen: GeneratorConfig, env: EnvConfig) -> WorldConfig:
    """The world of ``seed`` (same seed, config and camera: the same world, bit for bit)."""
    return build(WorldConfig, world_tree(seed, gen, env), "world")


def world_tree(seed: int, gen: GeneratorConfig, env: EnvConfig) -> dict:
    """The world of ``seed`` as the mapping a world YAML file holds."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ConfigError(f"world seed must be a non-negative integer, got {seed!r}")
    clear = 2 * (env.robot.body_radius + gen.clutter.path_clearance)
    if gen.width[1] < clear:
        raise ConfigError(
            f"generator.width {list(gen.width)} m: every corridor would be narrower than the "
            f"robot needs (2 x (robot.body_radius + clutter.path_clearance) = {clear:g} m)",
            "generator.width",
        )
    rng = np.random.default_rng(int(seed))
    view = CameraView.from_env_config(env)
    no_path = 0  # attempts whose main path did not fit (the rest: no landmark placement)
    for _ in range(gen.attempts):
        layout = _main_path(rng, gen)
        if layout is None:
            no_path += 1
            continue
        points, widths, rects = layout
        branches = _branches(rng, gen, points, widths, rects)
        arms = _junction_arms(rng, gen, points, widths, rects + branches)
        walls = boundary_walls(rects + branches + arms, gen.world.wall_thickness)
        obstacles = _clutter(rng, gen, env.robot.body_radius, points, widths)
        route = _route(rng, gen, points)
        landmarks = _landmarks(rng, gen, view, points, walls, obstacles)
        if landmarks is None or route is None:
            continue
        return _tree(seed, gen, points, walls, landmarks, obstacles, route)
    if no_path == gen.attempts:
        raise GenerationError(
            f"world seed {seed}: no main path of at least min_path_length "
            f"{gen.min_path_length:g} m fitted in {gen.attempts} attempts (segments, "
            "segment_length, width, end_margin and min_gap leave no room); widen those ranges"
        )
    raise GenerationError(
        f"world seed {seed}: no layout with the landmark coverage "
        f"{list(gen.visibility.coverage)} (a landmark in view along the lit path) in "
        f"{gen.attempts} attempts ({no_path} main paths did not fit, the other layouts had no "
        "board placement of that coverage); widen the visibility ranges or the corridors"
    )


def _snap(value: float, grid: float) -> float:
    return round(round(value / grid) * grid, CAP)


def _main_path(rng, gen: GeneratorConfig):
    """Vertices, widths and free-space rectangles of the main path, or None."""
    count = int(rng.integers(gen.segments[0], gen.segments[1] + 1))
    halls = _hall_legs(rng, gen, count)
    overrun = gen.end_margin
    if gen.goal_overrun is not None:  # the corridor goes on past the goal: no end wall at it
        overrun = _snap(rng.uniform(*gen.goal_overrun), gen.grid)
    points, widths, rects, heading = [np.zeros(2)], [], [], 0
    for leg in range(count):
        for _ in range(20):
            turn = 0 if leg == 0 else int(rng.choice([-1, 1]))
            length = _snap(rng.uniform(*gen.segment_length), gen.grid)
            width = _snap(rng.uniform(*(gen.hall_width if leg in halls else gen.width)), gen.grid)
            end = np.round(points[-1] + length * DIRECTIONS[(heading + turn) % 4], CAP)
            back = gen.end_margin if leg == 0 else width / 2
            ahead = width / 2
            if leg == count - 1:  # a goal in a hall stands in its middle, far from the walls
                ahead = max(overrun, width / 2) if leg in halls else overrun
            rect = Rect.around(points[-1], end, width / 2, back, ahead)
            # legs that do not meet keep min_gap apart; the last leg's end cap too
            if all(rect.gap(r) >= gen.min_gap for r in rects[:-1]):
                break
        else:
            return None
        heading = (heading + turn) % 4
        points.append(end)
        widths.append(width)
        rects.append(rect)
    points = np.array(points)
    if np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)) < gen.min_path_length:
        return None
    return points, widths, rects


def _hall_legs(rng, gen: GeneratorConfig, count: int) -> set[int]:
    """Main legs that are open halls (``hall_width`` wide): the last one (so the goal stands in
    a hall) and others drawn at random; none (and nothing drawn) when ``halls`` is [0, 0]."""
    if gen.halls[1] == 0:
        return set()
    number = min(int(rng.integers(gen.halls[0], gen.halls[1] + 1)), count)
    if number == 0:
        return set()
    others = rng.choice(count - 1, number - 1, replace=False) if number > 1 else []
    return {count - 1, *(int(leg) for leg in others)}


def _junction_arms(rng, gen: GeneratorConfig, points, widths, rects) -> list[Rect]:
    """Look-alike corridors at each turn: straight on (the incoming corridor continued) and to
    the side opposite the turn (the outgoing corridor mirrored), ``arm_length`` long, so the
    walls do not say which way the path goes; none (nothing drawn) when ``junction_arms`` is
    [0, 0]. An arm that would come within ``min_gap`` of another corridor is left out."""
    if gen.junction_arms[1] == 0:
        return []
    added: list[Rect] = []
    for turn in range(1, len(points) - 1):
        vertex = points[turn]
        incoming = (vertex - points[turn - 1]) / np.linalg.norm(vertex - points[turn - 1])
        outgoing = (points[turn + 1] - vertex) / np.linalg.norm(points[turn + 1] - vertex)
        options = [
            (incoming, widths[turn - 1], widths[turn]),  # direction, width, crossing width
            (-outgoing, widths[turn], widths[turn - 1]),
        ]
        number = int(rng.integers(gen.junction_arms[0], gen.junction_arms[1] + 1))
        for choice in rng.permutation(len(options))[:number]:
            direction, width, crossing = options[int(choice)]
            length = _snap(rng.uniform(*gen.arm_length), gen.grid)
            end = np.round(vertex + (crossing / 2 + length) * direction, CAP)
            rect = Rect.around(vertex, end, width / 2, 0.0, 0.0)
            others = [r for i, r in enumerate(rects) if i not in (turn - 1, turn)]
            if all(rect.gap(r) >= gen.min_gap for r in others + added):
                added.append(rect)
    return added


def _route(rng, gen: GeneratorConfig, points) -> list[list[float]] | None:
    """Goals visited in order (a delivery round): ``route_goals`` points on the path at least
    ``route_spacing`` apart (and from the start), then the path's end; [] (nothing drawn)
    when ``route_goals`` is [0, 0]; None when they do not fit."""
    if gen.route_goals[1] == 0:
        return []
    legs = np.linalg.norm(np.diff(points, axis=0), axis=1)
    offsets = np.concatenate([[0.0], np.cumsum(legs)])
    number = int(rng.integers(gen.route_goals[0], gen.route_goals[1] + 1))
    arcs = np.sort([_snap(a, gen.grid) for a in rng.uniform(0, offsets[-1], number)])
    if np.any(np.diff(np.concatenate([[0.0], arcs, [offsets[-1]]])) < gen.route_spacing):
        return None
    goals = []
    for arc in arcs:
        leg = min(int(np.searchsorted(offsets, arc, side="right")) - 1, len(legs) - 1)
        at = points[leg] + (arc - offsets[leg]) / legs[leg] * (points[leg + 1] - points[leg])
        goals.append([round(float(v), CAP) for v in at])
    return [*goals, [round(float(v), CAP) for v in points[-1]]]


def _branches(rng, gen: GeneratorConfig, points, widths, rects) -> list[Rect]:
    """Dead-end side branches off the main path that keep ``min_gap`` from other legs."""
    added: list[Rect] = []
    for _ in range(int(rng.integers(gen.branches[0], gen.branches[1] + 1))):
        leg = int(rng.integers(len(widths)))
        a, b = points[leg], points[leg + 1]
        along = (b - a) / np.linalg.norm(b - a)
        width = _snap(rng.uniform(*gen.width), gen.grid)
        length = _snap(rng.uniform(*gen.branch_length), gen.grid)
        past_turn = leg < len(widths) - 1 and rng.random() < 0.5
        if past_turn:  # straight on past the turn
            root, direction = b, along
            reach = widths[leg] / 2 + length
        else:  # perpendicular, from the middle of the leg
            root = np.round(a + _snap(np.linalg.norm(b - a) / 2, gen.grid) * along, CAP)
            direction = along[::-1] * rng.choice([[1, -1], [-1, 1]])
            reach = widths[leg] / 2 + length
        end = np.round(root + reach * direction, CAP)
        rect = Rect.around(root, end, width / 2, 0.0, 0.0)
        meets = {leg, leg + 1} if past_turn else {leg}  # the legs the branch opens into
        others = [r for i, r in enumerate(rects) if i not in meets]
        if all(rect.gap(r) >= gen.min_gap for r in others + added):
            added.append(rect)
    return added


def _clutter(rng, gen: GeneratorConfig, body_radius: float, points, widths) -> list[dict]:
    """Boxes and cylinders against the walls of main legs, off the path and the turns."""
    cfg = gen.clutter
    obstacles: list[dict] = []
    for _ in range(int(rng.integers(cfg.count[0], cfg.count[1] + 1))):
        leg = int(rng.integers(len(widths)))
        a, b = points[leg], points[leg + 1]
        length = float(np.linalg.norm(b - a))
        keep = widths[leg] / 2 + cfg.corner_distance
        if length <= 2 * keep:
            continue
        along = (b - a) / length
        size = float(rng.uniform(*cfg.size))
        room = widths[leg] / 2 - body_radius - cfg.path_clearance - 0.02  # 2 cm off the wall
        size = round(min(size, room), CAP)
        if size < cfg.size[0]:
            continue
        side = float(rng.choice([-1.0, 1.0]))
        offset = widths[leg] / 2 - 0.02 - size / 2
        at = a + rng.uniform(keep, length - keep) * along + side * offset * along[::-1] * [-1, 1]
        height = round(float(rng.uniform(*cfg.height)), CAP)
        if rng.random() < 0.5:
            yaw = round(math.degrees(math.atan2(along[1], along[0])), CAP)
            spec = {"shape": "box", "size": [size, size, height], "yaw_deg": yaw}
        else:
            spec = {"shape": "cylinder", "size": [round(size / 2, CAP), height]}
        spec["position"] = [round(float(v), CAP) for v in at]
        if all(np.hypot(*np.subtract(spec["position"], o["position"])) > size for o in obstacles):
            obstacles.append(spec)
    return obstacles


def _landmarks(rng, gen, view, points, walls, obstacles) -> list[dict] | None:
    """Landmarks chosen among wall candidates so every path point sees one (or, with the
    density dial below 1, every path point outside the dark stretches), or None."""
    pattern, vis = gen.world.landmark_pattern, gen.visibility
    margin = pattern.size / 2 + gen.world.wall_thickness  # the board stays on its wall
    candidates = []
    for (x1, y1, x2, y2), inward in walls:
        a, b = np.array([x1, y1]), np.array([x2, y2])
        length = float(np.linalg.norm(b - a))
        if length < 2 * margin:
            continue
        count = int((length - 2 * margin) // vis.candidate_step) + 1
        spare = (length - 2 * margin - (count - 1) * vis.candidate_step) / 2
        for k in range(count):
            at = a + (margin + spare + k * vis.candidate_step) * (b - a) / length
            candidates.append((np.round(at, CAP), np.array(inward)))
    if not candidates:
        return None
    normals = np.array([n for _, n in candidates])
    centres = board_centres([at for at, _ in candidates], normals, gen.world.wall_thickness)
    samples, headings = path_samples(points, vis.sample_step)
    circles = np.array([(*o["position"], _radius(o)) for o in obstacles], dtype=float).reshape(
        -1, 3
    )
    seen = seen_matrix(
        samples,
        headings,
        centres,
        normals,
        np.array([w for w, _ in walls], dtype=float),
        circles,
        gen.world.wall_thickness,
        pattern.size,
        gen.world.landmark_height,
        view,
        vis,
    )
    if vis.sparse:
        chosen = _sparse_cover(rng, vis, seen, sample_arc_lengths(points, vis.sample_step))
    else:
        chosen = choose_landmarks(seen, vis.landmarks_in_view)
    if chosen is None or len(chosen) > pattern.max_id:
        return None
    return [
        {
            "id": i + 1,
            "at": [float(v) for v in candidates[c][0]],
            "facing_deg": round(math.degrees(math.atan2(*candidates[c][1][::-1])), CAP),
        }
        for i, c in enumerate(chosen)
    ]


def _sparse_cover(rng, vis, seen: np.ndarray, arcs: np.ndarray) -> list[int] | None:
    """The density dial: draw a coverage ``c`` in ``vis.coverage``, lay dark stretches of
    ``vis.dark_stretch`` metres (whole ones, while they fit in ``(1 - c)`` of the path) at
    random places between lit gaps, keep only candidates no dark sample sees, and cover the lit
    samples that see any of those. None unless the measured coverage lies in ``vis.coverage``
    (boards near a stretch's end light less than planned: the layout is then drawn again)."""
    length = float(arcs[-1])
    dark_total = (1.0 - rng.uniform(*vis.coverage)) * length
    stretches: list[float] = []
    while True:
        stretch = float(rng.uniform(*vis.dark_stretch))
        if sum(stretches) + stretch > dark_total:
            break
        stretches.append(stretch)
    gaps = rng.dirichlet(np.ones(len(stretches) + 1)) * (length - sum(stretches))
    dark, at = np.zeros(len(arcs), bool), 0.0
    for gap, stretch in zip(gaps, stretches, strict=False):
        at += gap
        dark |= (arcs >= at) & (arcs <= at + stretch)
        at += stretch
    allowed = np.flatnonzero(~seen[dark].any(axis=0))
    lit = ~dark & seen[:, allowed].any(axis=1)
    chosen = choose_landmarks(seen[lit][:, allowed], vis.landmarks_in_view)
    chosen = sorted(int(allowed[c]) for c in chosen or [])
    fraction = coverage_of(seen[:, chosen].any(axis=1), arcs).fraction
    return chosen if vis.coverage[0] <= fraction <= vis.coverage[1] else None


def _radius(obstacle: dict) -> float:
    size = obstacle["size"]
    return size[0] if obstacle["shape"] == "cylinder" else math.hypot(size[0], size[1]) / 2


def _tree(seed, gen: GeneratorConfig, points, walls, landmarks, obstacles, route) -> dict:
    fixed = gen.world
    pattern = fixed.landmark_pattern
    tree = {
        "name": f"generated-{seed}",
        "wall_height": fixed.wall_height,
        "wall_thickness": fixed.wall_thickness,
        "walls": [[round(v, CAP) for v in w] for w, _ in walls],
        "path": [[round(float(v), CAP) for v in p] for p in points],
        "start": [0.0, 0.0, 0.0],
        "goal_radius": fixed.goal_radius,
        "landmark_height": fixed.landmark_height,
        "landmark_pattern": {
            "square_size": pattern.square_size,
            "pitch": pattern.pitch,
            "grid": pattern.grid,
            "border": pattern.border,
        },
        "landmarks": landmarks,
        "obstacles": obstacles,
    }
    if route:
        tree["route"] = route
    return tree


def path_clearance(world: WorldConfig, step: float = 0.05) -> float:
    """Smallest distance (m) from the path to a wall face or an obstacle: the robot, a disc of
    ``body_radius``, passes along the whole path when this exceeds its radius."""
    samples, _ = path_samples(np.asarray(world.path, float), step)
    walls = np.asarray(world.walls, float)
    a, d = walls[:, :2], walls[:, 2:] - walls[:, :2]
    rel = samples[:, None] - a[None]
    t = np.clip(np.sum(rel * d, -1) / np.sum(d * d, -1), 0, 1)
    wall_gap = np.linalg.norm(rel - t[..., None] * d, axis=-1).min() - world.wall_thickness / 2
    gaps = [obstacle_distance(p, o) for o in world.obstacles for p in samples]
    return float(min([wall_gap, *gaps]))
