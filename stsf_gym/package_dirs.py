"""The repository's folders that make the one import namespace ``stsf_gym``.

The repository keeps ``envs/``, ``agents/`` and ``configs/`` at its top level (as its owner
asked) and maps them into the package; a wheel installs them all under ``stsf_gym/``.
:data:`PACKAGE_DIRS` is that mapping, written once for the code: the layer check, the docs'
API pages, the provenance of results (a module's repository path, the same from a checkout
and a wheel), the step bench's ``--baseline`` checkout and config paths in errors all read it
from here. setuptools reads no Python, so ``pyproject.toml`` states it too
(``[tool.setuptools] package-dir``), for the build only; ``tests/test_layers.py`` fails when
that copy differs from this one.
"""

from __future__ import annotations

#: Import package -> the repository folder it lives in.
PACKAGE_DIRS: dict[str, str] = {
    "stsf_gym": "stsf_gym",
    "stsf_gym.envs": "envs",
    "stsf_gym.agents": "agents",
    "stsf_gym.configs": "configs",
}
#: The top-level folders mapped into ``stsf_gym`` (beside ``stsf_gym/`` itself).
MAPPED_FOLDERS: tuple[str, ...] = tuple(
    folder for package, folder in PACKAGE_DIRS.items() if package != "stsf_gym"
)
