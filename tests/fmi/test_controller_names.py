"""A shipped controller connects to its plant name to name: inputs are plant outputs, outputs plant inputs, same units.

For FMI 3.0 and 2.0 the two modelDescriptions are generated (no compile) and read with fmpy:
every controller input is an output of the plant with the same name and unit, every controller
output an input of the plant, the plant has no input the controller leaves open but those listed
in OPEN_INPUTS (attitude_torque_pd leaves torque_driven's world-frame torque to the system: the
disturbance is the plant's environment, not the controller's output), and each output
declares as dependencies (direct feedthrough: the sampled-data law reads the current inputs) only
inputs, and every input its law reads (the structural Jacobian of the generated ctrl_output; the
declaration may hold more, e.g. attitude_pd's u_x lists all of w_body, which a diagonal I_r and
G = 1 of reaction_wheel_slew leave unread: conservative for a master's loop detection).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from fmpy import read_model_description

from fmu.build.controller_description import fmi2_controller_description, fmi3_controller_description
from fmu.build.model_description import fmi2_model_description, fmi3_model_description
from modelsrc.controllers.controller import CKind
from modelsrc.controllers.controller_file import controller_path, list_controllers, load_controller
from modelsrc.model import build_model
from modelsrc.scene import load_scene


def descriptions(tmp_path: Path, name: str, version: int):
    """The ControllerModel and the (plant, controller) fmpy ModelDescriptions of the controller `name`."""
    path = controller_path(name)
    plant = tomllib.loads(path.read_text(encoding="utf-8"))["plant"]
    scene = load_scene(path.parent / plant if plant.endswith(".toml") else plant)
    model, ctrl = build_model(scene), load_controller(name)
    xml = {
        "plant": fmi3_model_description(model, "{t}") if version == 3 else fmi2_model_description(model, "{t}"),
        "ctrl": fmi3_controller_description(ctrl, "{t}")
        if version == 3
        else fmi2_controller_description(ctrl, "{t}", []),
    }
    out = []
    for k, b in xml.items():
        (tmp_path / f"{k}.xml").write_bytes(b)
        out.append(read_model_description(str(tmp_path / f"{k}.xml"), validate=False))
    return ctrl, out


OPEN_INPUTS = {"attitude_torque_pd": {f"tau_world[{i}]" for i in (1, 2, 3)}}


@pytest.mark.parametrize("version", [3, 2])
@pytest.mark.parametrize("name", list_controllers())
def test_a_controller_connects_to_its_plant_by_name_and_unit(tmp_path, name, version):
    law, (plant, ctrl) = descriptions(tmp_path, name, version)
    pv = {v.name: v for v in plant.modelVariables}
    ins = [v for v in ctrl.modelVariables if v.causality == "input"]
    outs = [v for v in ctrl.modelVariables if v.causality == "output"]
    assert ins and outs
    for v in ins:
        assert v.name in pv and pv[v.name].causality == "output", v.name
        assert (v.unit, v.type) == (pv[v.name].unit, pv[v.name].type), v.name
    for v in outs:
        assert v.name in pv and pv[v.name].causality == "input", v.name
        assert (v.unit, v.type) == (pv[v.name].unit, pv[v.name].type), v.name
    plant_inputs = {v.name for v in plant.modelVariables if v.causality == "input"}
    assert plant_inputs - OPEN_INPUTS.get(name, set()) == {v.name for v in outs}
    deps = {u.variable.name: {d.name for d in (u.dependencies or [])} for u in ctrl.outputs}
    u_names = [v.name for v in law.variables if v.kind == CKind.INPUT]
    jac = law.functions["ctrl_output"].sparsity_jac("u", "y")
    reads = {v.name: {u_names[j] for i, j in zip(*jac.get_triplet()) if i == k} for k, v in enumerate(outs)}
    ins_names = {v.name for v in ins}
    assert all(reads[o] <= deps[o] <= ins_names and reads[o] for o in deps), (deps, reads)
