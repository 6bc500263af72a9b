"""Every public name has one import path: the repository imports ``ConfigError`` and
``deep_merge`` from the module that defines them, and no other module re-exports them."""

from __future__ import annotations

import ast
import importlib
import subprocess

import pytest
from helpers import ROOT

HOMES = {"ConfigError": "stsf_gym.validation", "deep_merge": "stsf_gym.config_files"}


def _imports() -> list[tuple[str, int, str, str]]:
    """``(file, line, module, name)`` of every ``from module import name`` in the repository."""
    files = subprocess.run(
        ["git", "ls-files", "*.py"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    found = []
    for file in files:
        for node in ast.walk(ast.parse((ROOT / file).read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                found += [(file, node.lineno, node.module, a.name) for a in node.names]
    return found


def test_each_name_is_imported_from_its_home():
    strays = [
        f"{file}:{line} imports {name} from {module}"
        for file, line, module, name in _imports()
        if name in HOMES and module != HOMES[name]
    ]
    assert strays == []


@pytest.mark.parametrize("module", ["stsf_gym.config", "stsf_gym.envs.config"])
def test_no_facade_re_exports_them(module):
    assert not set(HOMES) & set(importlib.import_module(module).__all__)
