"""Shared fixtures: every shipped scene's FMU, built once per test session, for the tests in every folder."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from fmu.build.build_fmu import build_fmu
from modelsrc.scene import list_scenes, load_scene

from .harness.scenes import shared_fmu

# pytest-xdist's worker name (gw0, gw1, ...); absent in a run without -n
WORKER = os.environ.get("PYTEST_XDIST_WORKER", "")


@pytest.fixture(scope="session")
def build_dir(tmp_path_factory) -> Path:
    """The shipped scenes' FMUs of this run: one directory shared by the xdist workers (the
    parent of their own temporary directories), so that each FMU is built once per run."""
    if not WORKER:
        return tmp_path_factory.mktemp("fmus")
    shared = tmp_path_factory.getbasetemp().parent / "fmus"
    shared.mkdir(exist_ok=True)
    return shared


@pytest.fixture(scope="session")
def fmus(build_dir) -> dict[str, Path]:
    """Scene name -> path of its FMU, built in this run. Under xdist each scene is built
    under a lock by the first worker that needs it (the workers start from opposite ends
    of the list, so that two build at once) and reused by the others."""
    names = list_scenes()
    if WORKER and int(WORKER.removeprefix("gw") or 0) % 2:
        names = names[::-1]
    paths = {name: shared_fmu(build_dir, name) for name in names}
    return {name: paths[name] for name in list_scenes()}


# The extreme-case FMUs (tests/robustness/test_extreme_spin.py, tests/robustness/test_extreme_bodies.py): the
# extreme_free test FMU and the shipped sleeping_top, through ctypes (tests/harness/extreme_harness.py).
@pytest.fixture(scope="session")
def free(tmp_path_factory):
    from .harness.extreme_harness import Lib

    return Lib("extreme_free", tmp_path_factory.mktemp("extreme"))


@pytest.fixture(scope="session")
def top(tmp_path_factory):
    from .harness.extreme_harness import Lib

    return Lib("sleeping_top", tmp_path_factory.mktemp("top"))


# The FMI misuse tests' libraries (tests/robustness/test_fmi_misuse*.py), shared per session.
@pytest.fixture(scope="session")
def free_lib():
    """extreme_free: free principal body, torque inputs, friction (tests/harness/fmi3_ctypes.py)."""
    from .harness.fmi3_ctypes import shared_library

    return shared_library("extreme_free")


@pytest.fixture(scope="session")
def top_lib():
    """The shipped sleeping_top: gravity (mass, r_cm, g) and friction."""
    from .harness.fmi3_ctypes import shared_library

    return shared_library("sleeping_top")


@pytest.fixture(scope="session")
def fmi2_fmus(tmp_path_factory) -> dict[str, Path]:
    """FMI 2.0 archives (host binary only) of two scenes: heavy_top (gravity) and
    skewed_bar (the smallest generated C), for the source-FMU and co-simulation master tests."""
    out = tmp_path_factory.mktemp("fmus2")
    return {name: build_fmu(load_scene(name), out, fmi_version=2) for name in ("heavy_top", "skewed_bar")}


@pytest.fixture(scope="session")
def torque_driven_fmi2(tmp_path_factory) -> Path:
    """The shipped torque_driven scene as an FMI 2.0 archive (host binary only), for the
    tests of input and output derivatives (tests/fmi/test_inputs_inside_step_fmi2.py, test_output_derivatives.py)."""
    return build_fmu(load_scene("torque_driven"), tmp_path_factory.mktemp("fmus2_torque"), fmi_version=2)
