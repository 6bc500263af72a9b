"""MkDocs hooks: the API reference, generated from the package's folders, and the docstring check.

The repository keeps ``envs/``, ``agents/`` and ``configs/`` beside ``stsf_gym/`` and maps them
into the one namespace (:data:`stsf_gym.layers.PACKAGE_DIRS`), which a static reader such
as griffe cannot follow. The hooks therefore lay the namespace out as it is installed, in
symbolic links under ``build/api-src/`` (read by mkdocstrings through its ``paths`` option), and
add one page per package to the navigation: the packages and modules are
:func:`stsf_gym.layers.packages`, the same that ``python -m stsf_gym.layers --tree`` prints, so
a new module or folder is documented without an edit here.

:func:`on_pre_build` fails a strict build (a warning) for every public module, class, function
or method without a docstring. A method that overrides a documented method of a base class in
the package counts as documented (the base class's docstring is the contract).
"""

from __future__ import annotations

import functools
import logging
import re
import shutil
import subprocess
import sys
from pathlib import Path

import griffe
from mkdocs.structure.files import File

from stsf_gym.layers import PACKAGE_DIRS, ROOT, packages

log = logging.getLogger("mkdocs.plugins.stsf_gym")
STAGE = ROOT / "build" / "api-src"
REFERENCE = "reference"
LAYERS_MARK = "<!-- layers: the output of python -m stsf_gym.layers -->"


def stage_namespace(stage: Path = STAGE) -> Path:
    """``stage/stsf_gym``: the installed layout of the package as links into the checkout."""
    if stage.exists():
        shutil.rmtree(stage)
    for package, folder in PACKAGE_DIRS.items():
        target = stage.joinpath(*package.split("."))
        target.parent.mkdir(parents=True, exist_ok=True)
        if package == "stsf_gym":
            target.mkdir()
            for entry in (ROOT / folder).iterdir():
                if entry.name == "__init__.py":  # a copy: a reader resolving a link to it
                    shutil.copy(entry, target / entry.name)  # would list stsf_gym/ instead
                elif entry.name != "__pycache__":
                    (target / entry.name).symlink_to(entry)
        else:
            target.symlink_to(ROOT / folder, target_is_directory=True)
    return stage


@functools.cache
def load_package() -> griffe.Module:
    """The staged package, read statically (nothing is imported)."""
    return griffe.load(
        "stsf_gym",
        search_paths=[str(STAGE)],
        try_relative_path=False,
        allow_inspection=False,
        resolve_aliases=True,
    )


def defined_here(module: griffe.Module) -> list[str]:
    """The public names ``module`` defines itself (not those it imports)."""
    return [
        name
        for name, member in module.members.items()
        if not (member.is_alias or member.is_module or name.startswith("_"))
    ]


def reference_pages() -> dict[str, str]:
    """Page path -> Markdown: one page per package, a section per module of its folder. A
    package's own section shows only what its ``__init__`` defines, not what it re-exports
    (that is in its module's section)."""
    root, pages = load_package(), {}
    for package, modules in packages(ROOT).items():
        lines = [f"# `{package}`", ""]
        for module in modules:
            name = package if module == "__init__" else f"{package}.{module}"
            lines += [f"::: {name}", "    options:", "      show_submodules: false"]
            if module == "__init__":
                own = defined_here(
                    root[name.removeprefix("stsf_gym").lstrip(".")] if name != "stsf_gym" else root
                )
                lines.append(f"      members: {own or 'false'}")
            lines.append("")
        pages[f"{REFERENCE}/{package}.md"] = "\n".join(lines)
    return pages


class SphinxRoles(griffe.Extension):
    """Griffe extension (mkdocs.yml): reST roles in docstrings (``:func:`name```) as code."""

    ROLE = re.compile(r":(?:func|class|meth|mod|attr|data|exc|obj|const):`~?\.?([^`]+)`")

    def on_object(self, *, obj: griffe.Object, **kwargs) -> None:
        """Rewrite the roles of ``obj``'s docstring."""
        if obj.docstring is not None:
            obj.docstring.value = self.ROLE.sub(r"`\1`", obj.docstring.value)


def on_startup(command, dirty):
    """Stage the namespace (``paths: [build/api-src]`` in mkdocs.yml) before any plugin reads it."""
    stage_namespace()


def on_config(config):
    """Add the API reference to the navigation."""
    nav = [{Path(page).stem: page} for page in reference_pages()]
    config["nav"].append({"API reference": [{"Layout and layers": f"{REFERENCE}/index.md"}, *nav]})
    return config


def on_files(files, config):
    """Add the generated reference pages."""
    for path, text in reference_pages().items():
        files.append(File.generated(config, path, content=text))
    return files


def on_page_markdown(markdown, page, config, files):
    """Put the live output of ``python -m stsf_gym.layers`` where a page asks for it."""
    if LAYERS_MARK not in markdown:
        return markdown
    done = subprocess.run(
        [sys.executable, "-m", "stsf_gym.layers"], capture_output=True, text=True, cwd=ROOT
    )
    if done.returncode != 0:
        log.warning("python -m stsf_gym.layers failed:\n%s%s", done.stdout, done.stderr)
    return markdown.replace(LAYERS_MARK, f"```text\n{done.stdout.rstrip()}\n```")


def _documented_in_base(method: griffe.Object) -> bool:
    try:
        bases = method.parent.mro()
    except ValueError:  # a base class outside the package
        return False
    for base in bases:
        found = base.members.get(method.name)
        if found is not None and not found.is_alias and found.has_docstring:
            return True
    return False


def undocumented(package: griffe.Module) -> list[str]:
    """Public names of ``package`` (recursively) without a docstring."""
    missing: list[str] = []

    def public(name: str) -> bool:
        return not name.startswith("_")

    def visit(module: griffe.Module) -> None:
        if not module.has_docstring:
            missing.append(f"module {module.path}")
        for name, member in module.members.items():
            if member.is_alias or not (public(name) or member.is_module):
                continue
            if member.is_module:
                visit(member)
            elif member.is_class:
                if not member.has_docstring:
                    missing.append(f"class {member.path}")
                for method_name, method in member.members.items():
                    if method.is_alias or not public(method_name) or not method.is_function:
                        continue
                    if not method.has_docstring and not _documented_in_base(method):
                        missing.append(f"method {method.path}")
            elif member.is_function and not member.has_docstring:
                missing.append(f"function {member.path}")

    visit(package)
    return missing


def on_pre_build(config):
    """Warn (a failure under ``--strict``) for every public name without a docstring."""
    for name in undocumented(load_package()):
        log.warning("no docstring: %s", name)
