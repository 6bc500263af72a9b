"""The package reads its shipped agents through a manifest of SHA-256 digests: the committed
manifest lists every shipped file as it is, a ship rewrites it, and a model whose bytes it does
not list is refused before it is loaded."""

from __future__ import annotations

import shutil

import pytest

from stsf_gym.agents import pretrained
from stsf_gym.agents.pretrained.shipped_folder import MANIFEST, manifest, manifest_of
from stsf_gym.validation import ConfigError


def test_the_manifest_lists_every_shipped_file_as_it_is():
    listed = manifest(pretrained.MODELS)
    assert listed == manifest_of(pretrained.MODELS)["files"]
    assert "corridor/dagger-stsf/seed-0.zip" in listed and len(listed) > 20


def test_a_model_the_manifest_does_not_list_is_refused(tmp_path, monkeypatch):
    models = tmp_path / "trained-models"
    shutil.copytree(
        pretrained.MODELS / "corridor" / "dagger-stsf", models / "corridor" / "dagger-stsf"
    )
    shutil.copy(pretrained.MODELS / MANIFEST, models / MANIFEST)
    monkeypatch.setattr(pretrained, "MODELS", models)
    assert pretrained.models("pretrained:corridor/dagger-stsf")
    model = models / "corridor" / "dagger-stsf" / "seed-0.zip"
    model.write_bytes(model.read_bytes() + b"\0")
    with pytest.raises(ConfigError, match=r"not those .* lists"):
        pretrained.models("pretrained:corridor/dagger-stsf")
