"""The FMU archives: valid for fmpy, warning-free build, only what the scene uses."""

from __future__ import annotations

import ctypes
import re
import zipfile

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from fmu.build.build_fmu import build_fmu, platform_tuple
from modelsrc.scene import list_scenes, load_scene

from ..harness.scenes import write_scene

SCENES = list_scenes()
FMI3_HEADER_FUNCTIONS = 75  # FMI3_Export declarations in fmi3Functions.h


def test_all_scenes_shipped():
    assert set(SCENES) >= {"free_asymmetric", "symmetric_free", "heavy_top", "sleeping_top", "torque_driven"}


@pytest.mark.parametrize("scene", SCENES)
def test_validate_fmu_reports_no_problems(fmus, scene):
    assert validate_fmu(str(fmus[scene])) == []


@pytest.mark.parametrize("scene", SCENES)
def test_build_is_warning_free(fmus, build_dir, scene):
    # -Wall -Wextra on both files (-Werror on the hand-written layer); the log holds gcc's stderr
    assert not (build_dir / f"{scene}.build.log").exists()


def test_archive_layout_and_exports(fmus, tmp_path):
    path = fmus["heavy_top"]
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        z.extractall(tmp_path)
    so = f"binaries/{platform_tuple()}/heavy_top.so"
    for needed in (
        "modelDescription.xml",
        so,
        "sources/buildDescription.xml",
        "sources/rbfmu_fmi3.c",
        "sources/model_funcs.c",
        "sources/model_data.h",
        "sources/fmi3Functions.h",
    ):
        assert needed in names
    assert not any(n.endswith(".o") for n in names)
    header = (tmp_path / "sources/fmi3Functions.h").read_text()
    declared = re.findall(r"^FMI3_Export\s+\w+TYPE\s+(fmi3\w+);", header, re.M)
    assert len(declared) == FMI3_HEADER_FUNCTIONS
    lib = ctypes.CDLL(str(tmp_path / so))
    missing = [f for f in declared if not hasattr(lib, f)]
    assert missing == []
    # the CasADi functions stay internal (-fvisibility=hidden): no clash between FMUs in one process
    assert not hasattr(lib, "model_step")


def _names(md):
    return {v.name: v for v in md.modelVariables}


def test_free_scene_has_no_torque_gravity_or_friction_variables(fmus):
    v = _names(read_model_description(str(fmus["free_asymmetric"])))
    for absent in ("tau_body[1]", "tau_world[1]", "mass", "r_cm[1]", "g[3]", "c_friction", "E_total", "I[1,1]"):
        assert absent not in v
    assert {"I_principal[1]", "I_principal[2]", "I_principal[3]", "h_max"} <= set(v)


def test_heavy_top_has_gravity_but_no_torque_inputs(fmus):
    md = read_model_description(str(fmus["heavy_top"]))
    v = _names(md)
    assert {"mass", "r_cm[3]", "g[3]", "E_total"} <= set(v)
    assert not any(x.causality == "input" for x in md.modelVariables)
    assert "c_friction" not in v
    assert "c_friction" in _names(read_model_description(str(fmus["sleeping_top"])))


def test_torque_driven_inputs_and_units(fmus):
    md = read_model_description(str(fmus["torque_driven"]))
    inputs = sorted(x.name for x in md.modelVariables if x.causality == "input")
    assert inputs == sorted([f"tau_body[{i}]" for i in (1, 2, 3)] + [f"tau_world[{i}]" for i in (1, 2, 3)])
    v = _names(md)
    assert v["tau_body[1]"].unit == "N.m" and v["w_body[1]"].unit == "rad/s" and v["I_principal[1]"].unit == "kg.m2"
    assert v["q[1]"].initial == "exact" and v["E_kin"].initial == "calculated"
    assert md.defaultExperiment.stopTime == "8.0"
    assert md.coSimulation.canHandleVariableCommunicationStepSize


@pytest.mark.slow
def test_outputs_not_requested_are_absent(tmp_path):
    path = write_scene(
        tmp_path,
        """
outputs = ["E_kin"]
[body]
inertia = [[2.0, 0.1, 0.0], [0.1, 3.0, 0.0], [0.0, 0.0, 4.0]]
[initial]
w_body = [0.0, 1.0, 0.0]
""",
    )
    fmu = build_fmu(load_scene(path), tmp_path)
    md = read_model_description(str(fmu))
    outs = [x.name for x in md.modelVariables if x.causality == "output"]
    # the states (q, w_body) are always outputs; of the derived outputs only E_kin
    assert sorted(outs) == sorted([f"q[{i}]" for i in range(1, 5)] + [f"w_body[{i}]" for i in range(1, 4)] + ["E_kin"])
    # a full tensor gives the nine I[i,j] parameters
    assert {f"I[{i},{j}]" for i in (1, 2, 3) for j in (1, 2, 3)} <= set(_names(md))
    assert validate_fmu(str(fmu)) == []


def test_build_log_written_only_when_there_are_diagnostics(tmp_path):
    from fmu.build.build_fmu import _write_build_log

    log = tmp_path / "scene.build.log"
    _write_build_log(log, "model_funcs.c:3: warning: unused variable 'x'\n")
    assert log.read_text().startswith("model_funcs.c:3: warning")
    _write_build_log(log, "")  # a clean rebuild removes the previous build's log
    assert not log.exists()
    _write_build_log(log, "\n")
    assert not log.exists()
