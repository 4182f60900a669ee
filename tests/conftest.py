"""Shared fixtures: every shipped scene's FMU, built once per test session."""

from __future__ import annotations

from pathlib import Path

import pytest

from fmu.build_fmu import build_fmu
from modelsrc.scene import list_scenes, load_scene


@pytest.fixture(scope="session")
def build_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fmus")


@pytest.fixture(scope="session")
def fmus(build_dir) -> dict[str, Path]:
    """Scene name -> path of its freshly built FMU."""
    return {name: build_fmu(load_scene(name), build_dir) for name in list_scenes()}


def write_scene(tmp_path: Path, text: str, name: str = "custom") -> Path:
    """Write a scene file and return its path (for scenes made up by a test)."""
    p = tmp_path / f"{name}.toml"
    p.write_text(text)
    return p
