"""The project's import layers: the graph drawn from the code, and the rules it must keep.

``python -m stsf_gym.layers`` prints, for each layer, the layers its modules import (every
``import`` statement counts, inside functions too; for the rules those under
``if TYPE_CHECKING:`` do not, for import cycles they do), then any violation, and exits with
status 1 when there is one. The rules (:data:`ALLOWED`):

    stsf_gym.cli, stsf_gym.experiments -> stsf_gym.agents -> stsf_gym.wrappers
        -> stsf_gym.estimators (and .references)
        -> stsf_gym.fusion / vision / geometry / metrics / results / tum;
    stsf_gym.experiments, stsf_gym.bench -> stsf_gym.recording -> stsf_gym.wrappers (no envs);
    stsf_gym.envs (and its folders .worlds, .rendering) -> stsf_gym.vision.landmarks / geometry;
    stsf_gym.envs.rendering never imports PyBullet

plus the neutral leaves both sides share (``validation``, ``config_files``, ``io``, ``video``,
``terminal_table``, ``camera_model``: the lens model the simulator renders with and the
estimators undistort with). Also
checked: no module imports another's private (``_name``) name, no import cycle between
modules, every package folder names its one idea (the first paragraph of its ``__init__``'s
docstring: a folder per idea, however many modules the idea takes), and no module longer than
:data:`MODULE_LIMIT` lines unless :data:`LONG_MODULES` says why. ``python -m stsf_gym.layers
--tree`` prints the layout instead: each package, the repository folder it lives in, its idea
and its modules; ``python -m stsf_gym.layers
--picture`` draws the layers as rooms on floors (SVG, :mod:`stsf_gym.layer_picture`), the
picture of ``docs/reference/layers.svg``.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

from stsf_gym import layer_picture

ROOT = Path(__file__).resolve().parent.parent
#: Import package -> the repository folder it lives in: the repository keeps ``envs/``,
#: ``agents/`` and ``configs/`` at its top level (as its owner asked) and maps them into the one
#: namespace; a wheel installs them all under ``stsf_gym/``. Written here once for the code
#: (these checks, the docs' API pages, the provenance of results, the step bench's
#: ``--baseline`` checkout); setuptools reads no Python, so ``pyproject.toml``'s
#: ``[tool.setuptools] package-dir`` repeats it for the build, and
#: ``tests/package/test_layers.py`` fails when the two differ.
PACKAGE_DIRS = {
    "stsf_gym": "stsf_gym",
    "stsf_gym.envs": "envs",
    "stsf_gym.agents": "agents",
    "stsf_gym.configs": "configs",
}
#: The top-level folders mapped into ``stsf_gym`` (beside ``stsf_gym/`` itself).
MAPPED_FOLDERS = tuple(folder for package, folder in PACKAGE_DIRS.items() if package != "stsf_gym")
EXTERNAL = ("pybullet", "pybullet_utils")  # third-party layers the rules name
LEAVES = (
    "stsf_gym.geometry",
    "stsf_gym.validation",
    "stsf_gym.config_files",
    "stsf_gym.io",
    "stsf_gym.camera_model",
    "stsf_gym.video",
    "stsf_gym.terminal_table",
)
#: What the simulator side may use of the library, and its folders by idea.
ENV_SHARED = ("stsf_gym.geometry", "stsf_gym.vision.landmarks", *LEAVES[1:])
ENV_FOLDERS = ("stsf_gym.envs.worlds", "stsf_gym.envs.rendering")
#: Pure measurement code (numpy/scipy): metrics, the results schema, TUM trajectories.
MEASURES = ("stsf_gym.metrics", "stsf_gym.results", "stsf_gym.tum")
CORE = (*LEAVES, *MEASURES, "stsf_gym.fusion", "stsf_gym.vision", "stsf_gym.vision.landmarks")
ESTIMATION = (
    *CORE,
    "stsf_gym.estimators",
    "stsf_gym.estimators.references",
)
EPISODE = (
    *ESTIMATION,
    "stsf_gym",
    "stsf_gym.wrappers",
    "stsf_gym.episode_env",
    "stsf_gym.envs",
    *ENV_FOLDERS,
)
ANY = "*"

#: Each layer and the layers it may import, top to bottom.
ALLOWED: dict[str, tuple[str, ...] | str] = {
    "stsf_gym.cli": ANY,
    "stsf_gym.experiments": (*EPISODE, "stsf_gym.agents", "stsf_gym.config", "stsf_gym.recording"),
    "stsf_gym.bench": (
        *EPISODE,
        "stsf_gym.agents",
        "stsf_gym.experiments",
        "stsf_gym.recording",
        "stsf_gym.layers",  # a --baseline checkout's folders
    ),
    # recording: episode logs written from an env stack (duck-typed, never the simulator's
    # modules) and read back for replays, so a replay runs with no simulator
    "stsf_gym.recording": (*ESTIMATION, "stsf_gym.wrappers"),
    "stsf_gym.agents": EPISODE,
    "stsf_gym.config": ("stsf_gym.envs", "stsf_gym.validation", "stsf_gym.config_files"),
    "stsf_gym.episode_env": (
        "stsf_gym.wrappers",
        "stsf_gym.estimators",
        "stsf_gym.envs",
        *ENV_FOLDERS,
        "stsf_gym.config_files",  # env settings merged section by section
    ),
    "stsf_gym.wrappers": ESTIMATION,
    "stsf_gym": ("stsf_gym.config_files",),  # the __init__: registration (reads suite files)
    "stsf_gym.envs": (*ENV_SHARED, *ENV_FOLDERS, *EXTERNAL),
    # worlds: layouts, checks, the generator (numpy) and the PyBullet builder of a world
    "stsf_gym.envs.worlds": (*ENV_SHARED, "stsf_gym.envs", "stsf_gym.envs.rendering", *EXTERNAL),
    # rendering: the scene, GL renderer, map and window draw what the worlds describe; no PyBullet
    "stsf_gym.envs.rendering": (*ENV_SHARED, "stsf_gym.envs", "stsf_gym.envs.worlds"),
    "stsf_gym.configs": (),  # package data only
    "stsf_gym.estimators": CORE,
    # the references (smoother, MCL, the floor): estimators too, on GTSAM and numpy
    "stsf_gym.estimators.references": ESTIMATION,
    "stsf_gym.fusion": ("stsf_gym.geometry",),
    "stsf_gym.metrics": ("stsf_gym.geometry",),
    "stsf_gym.results": ("stsf_gym.layers",),  # the package's folders: a module's path
    "stsf_gym.tum": ("stsf_gym.io",),
    "stsf_gym.vision": ("stsf_gym.vision.landmarks", "stsf_gym.geometry"),
    "stsf_gym.vision.landmarks": (),
    "stsf_gym.config_files": ("stsf_gym.validation",),
    "stsf_gym.geometry": ("stsf_gym.validation",),  # ranges of the odometry calibration
    "stsf_gym.validation": (),
    "stsf_gym.io": (),
    # ranges of the camera mount; the undistortion's compiled loop
    "stsf_gym.camera_model": ("stsf_gym.validation", "stsf_gym.geometry"),
    "stsf_gym.video": ("stsf_gym.io",),  # written atomically with the umask's mode
    "stsf_gym.terminal_table": (),
    "stsf_gym.layers": ("stsf_gym.layer_picture",),
    "stsf_gym.layer_picture": (),  # the drawing: a graph in, SVG text out
}


#: Lines one module may hold; a longer one is listed in :data:`LONG_MODULES` with the reason.
MODULE_LIMIT = 400
LONG_MODULES = {
    "stsf_gym.envs.corridor_env": (
        "the env class: about 130 of its lines are the docstring that documents its spaces, "
        "reward and episode end (its API page), the rest is one step loop; its views (map, "
        "chase, top, the window) can leave the class next: the wrappers' estimates now reach "
        "the map through the render path (draw_on_map), not through the class's state"
    ),
}


def module_files(root: Path = ROOT) -> dict[str, Path]:
    """Every module of the project's packages under ``root`` (a checkout or an installed
    wheel's site folder), by dotted name."""
    files = {}
    for package, folder in PACKAGE_DIRS.items():
        base = root / folder if (root / folder).is_dir() else root / package.replace(".", "/")
        for path in sorted(base.rglob("*.py")):
            parts = (*package.split("."), *path.relative_to(base).with_suffix("").parts)
            files[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return files


def module_imports(root: Path = ROOT, type_only: bool = False) -> dict[str, list[tuple[str, str]]]:
    """For each module, the (module, name) pairs it imports: project modules and
    :data:`EXTERNAL` ones; ``name`` is the imported name of a ``from`` import ("" otherwise).
    Imports under ``if TYPE_CHECKING:`` count only with ``type_only``."""
    files = module_files(root)
    graph = {}
    for module, path in files.items():
        found = []
        for node in _imports(ast.parse(path.read_text(), str(path)), type_only):
            if isinstance(node, ast.Import):
                found += [(alias.name, "") for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                for alias in node.names:
                    submodule = f"{node.module}.{alias.name}"
                    found.append(
                        (submodule, "") if submodule in files else (node.module, alias.name)
                    )
        graph[module] = [(m, n) for m, n in found if m in files or _top(m) in EXTERNAL]
    return graph


def _imports(tree: ast.AST, type_only: bool) -> list[ast.Import | ast.ImportFrom]:
    """The import statements of ``tree``; those in ``if TYPE_CHECKING:`` blocks with
    ``type_only`` only."""
    skipped = (
        set()
        if type_only
        else {
            id(inner)
            for node in ast.walk(tree)
            if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
            for statement in node.body
            for inner in ast.walk(statement)
        }
    )
    return [
        node
        for node in ast.walk(tree)
        if isinstance(node, ast.Import | ast.ImportFrom) and id(node) not in skipped
    ]


def _top(module: str) -> str:
    return module.partition(".")[0]


def layer_of(module: str) -> str:
    """The layer of a module: the longest :data:`ALLOWED` key that is it or a parent of it."""
    if _top(module) in EXTERNAL:
        return _top(module)
    names = [key for key in ALLOWED if module == key or module.startswith(f"{key}.")]
    names = [key for key in names if key != "stsf_gym" or module == key]  # the __init__ only
    return max(names, key=len) if names else module


def layer_graph(imports: dict[str, list[tuple[str, str]]]) -> dict[str, set[str]]:
    """Layer -> the other layers its modules import."""
    graph: dict[str, set[str]] = {layer: set() for layer in ALLOWED}
    for module, targets in imports.items():
        source = layer_of(module)
        graph.setdefault(source, set()).update(
            layer_of(target) for target, _ in targets if layer_of(target) != source
        )
    return graph


def violations(root: Path = ROOT) -> list[str]:
    """Every broken rule, in words (empty when the layers hold)."""
    imports = module_imports(root)
    found = []
    for module, targets in sorted(imports.items()):
        source = layer_of(module)
        allowed = ALLOWED.get(source)
        if allowed is None:
            found.append(f"{module}: layer {source} has no rule in stsf_gym.layers.ALLOWED")
            continue
        for target, name in targets:
            layer = layer_of(target)
            if layer != source and allowed != ANY and layer not in allowed:
                found.append(f"{module} imports {target} ({source} -> {layer} is not allowed)")
            if name.startswith("_") and not name.startswith("__") and target != module:
                found.append(f"{module} imports the private name {target}.{name}")
    every = module_imports(root, type_only=True)  # a cycle of type-only imports is one too
    found += [f"import cycle: {' -> '.join(cycle)}" for cycle in import_cycles(every)]
    for module, path in module_files(root).items():
        lines = len(path.read_text().splitlines())
        if lines > MODULE_LIMIT and module not in LONG_MODULES:
            found.append(
                f"{module} holds {lines} lines (at most {MODULE_LIMIT}): split it by idea, or "
                "list it in stsf_gym.layers.LONG_MODULES with the reason"
            )
        elif lines <= MODULE_LIMIT and module in LONG_MODULES:
            found.append(f"{module} is no longer long: remove it from LONG_MODULES")
    files = module_files(root)
    for package in packages(root):
        if package in files and not folder_idea(files[package]):
            found.append(
                f"{package}: its __init__ has no docstring naming the folder's idea (its first "
                "paragraph): a folder holds one idea"
            )
    return list(dict.fromkeys(found))


def folder_idea(init: Path) -> str:
    """The idea of the package whose ``__init__`` is ``init``: its docstring's first paragraph,
    on one line."""
    doc = ast.get_docstring(ast.parse(init.read_text(), str(init))) or ""
    return " ".join(doc.strip().partition("\n\n")[0].split())


def packages(root: Path = ROOT) -> dict[str, list[str]]:
    """Each package (dotted name) and the modules directly in its folder (``__init__``
    first), sorted by package name."""
    found: dict[str, list[str]] = {}
    for module, path in module_files(root).items():
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        found.setdefault(package, []).append(
            "__init__" if path.name == "__init__.py" else path.stem
        )
    return {name: sorted(found[name], key=lambda m: (m != "__init__", m)) for name in sorted(found)}


def print_tree(root: Path = ROOT) -> None:
    """The layout: each package, its folder in the repository, its idea and its modules."""
    files = module_files(root)
    for package, modules in packages(root).items():
        folder = files[package].parent.relative_to(root) if package in files else "?"
        print(f"{package}  ({folder}/, {len(modules)} modules)")
        print(f"    {folder_idea(files[package]) if package in files else ''}")
        print(f"    {' '.join(modules)}")


def import_cycles(imports: dict[str, list[tuple[str, str]]]) -> list[list[str]]:
    """Cycles of modules importing each other (one per strongly connected group)."""
    edges = {m: sorted({t for t, _ in targets if t in imports}) for m, targets in imports.items()}
    cycles, state = [], {}

    def visit(module: str, path: list[str]) -> None:
        state[module] = "open"
        for target in edges[module]:
            if state.get(target) == "open":
                cycles.append([*path[path.index(target) :], target])
            elif target not in state:
                visit(target, [*path, target])
        state[module] = "done"

    for module in sorted(edges):
        if module not in state:
            visit(module, [module])
    return cycles


def picture(root: Path = ROOT) -> str:
    """The layers as rooms on floors (SVG, :func:`stsf_gym.layer_picture.svg`): the layer graph
    of the code under ``root``, each room's module count and the repository folder it lives
    in."""
    files = module_files(root)
    graph = layer_graph(module_imports(root))
    rooms = {layer_of(module) for module in files} | {t for ts in graph.values() for t in ts}
    graph = {room: graph.get(room, set()) & rooms for room in sorted(rooms)}
    modules, folders = {}, {}
    for module, path in files.items():
        room = layer_of(module)
        modules[room] = modules.get(room, 0) + 1
        folders[room] = path.relative_to(root).parts[0]
    return layer_picture.svg(graph, modules, folders)


def main() -> int:
    """``python -m stsf_gym.layers``: print the layer graph and any broken rule (exit code 1),
    the package tree with ``--tree``, or the picture (SVG) with ``--picture``.
    """
    if "--tree" in sys.argv[1:]:
        print_tree()
        return 0
    if "--picture" in sys.argv[1:]:
        print(picture(), end="")
        return 0
    graph = layer_graph(module_imports())
    width = max(map(len, graph))
    for layer, targets in graph.items():
        print(f"{layer:<{width}} -> {', '.join(sorted(targets)) or '(nothing)'}")
    problems = violations()
    print("\nviolations:", *(problems or ["none"]), sep="\n  ")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
