"""`rbfmu demo` builds the systems' component FMUs in its build queue (fmu.system.build.component_builds)."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import pytest

from fmu.build.build_fmu import run_builds
from fmu.system.build import check_built, component_builds
from modelsrc.errors import ModelInputError
from tests.system.conftest import write_system


def test_component_builds_are_the_fmus_build_system_uses(system_build_dir) -> None:
    """The tasks, run on worker processes, return the very FMUs that check_built found (FMI 2.0, reused:
    the archives are not rebuilt, their modification times stay)."""
    built = check_built("slew", system_build_dir)
    before = {n: p.stat().st_mtime_ns for n, p in built.fmus.items()}
    tasks = component_builds("slew", system_build_dir)
    with ProcessPoolExecutor(max_workers=2) as pool:
        got = run_builds(tasks, pool)
    assert got == list(built.fmus.values())
    assert all(p.name.endswith("_fmi2.fmu") for p in got)
    assert {n: p.stat().st_mtime_ns for n, p in built.fmus.items()} == before


def test_component_builds_refuse_an_unknown_component_before_any_build(tmp_path) -> None:
    path = write_system(tmp_path / "bad.toml", 'name = "s"\nstep = 0.1\n[components.plant]\nscene = "no_such_scene"\n')
    with pytest.raises(ModelInputError, match="component plant"):
        component_builds(path, tmp_path / "build")
    assert not (tmp_path / "build").exists()
