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


@pytest.fixture(scope="session")
def quadrotor_runs(system_build_dir, tmp_path_factory) -> dict:
    """The shipped quadrotor_hover system (two more FMUs, ~30 s to build, into the same cache)
    run to its stop time in ECOS and in libcosim: master -> SystemResult."""
    from fmu.system.archive import open_archive
    from fmu.system.build import build_system
    from fmu.system.masters import run_system

    archive = open_archive(build_system("quadrotor_hover", tmp_path_factory.mktemp("quadrotor"), system_build_dir))
    return {m: run_system(archive, m) for m in ("ecos", "libcosim")}


def write_system(path: Path, text: str) -> Path:
    """A system file with the given TOML text."""
    path.write_text(text)
    return path
