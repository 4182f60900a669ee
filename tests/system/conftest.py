"""The slew system's component FMUs (FMI 2.0), built once per session for the tests of systems."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def system_build_dir(tmp_path_factory) -> Path:
    """A build cache holding reaction_wheel_slew_fmi2.fmu and attitude_pd_fmi2.fmu (ensure_fmu reuses them)."""
    from fmu.system.build import check_built

    d = tmp_path_factory.mktemp("system_fmus")
    check_built("slew", d)
    return d


def write_system(path: Path, text: str) -> Path:
    """A system file with the given TOML text."""
    path.write_text(text)
    return path
