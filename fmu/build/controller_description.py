"""modelDescription.xml (FMI 3.0 or 2.0, Co-Simulation only) of a sampled-data controller FMU.

Inputs are continuous (the plant's outputs), outputs discrete (held between sample points,
initial calculated), the discrete states local, the gains, limits and target tunable
parameters, the sample period Ts a fixed one. Each output's direct dependencies on the
inputs are declared (ModelStructure), so that a master can order the evaluation of a loop.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

from modelsrc.controllers.controller import CKind, ControllerModel, CVar

from .model_description import UNITS, root_element

CONTROLLER_UNITS = {**UNITS, "1/s2": {"s": -2}, "1/s3": {"s": -3}, "rad.s": {"rad": 1, "s": 1}, "m.s": {"m": 1, "s": 1}}
# kind -> (causality, variability, initial)
CAUSALITY = {
    CKind.INDEPENDENT: ("independent", "continuous", None),
    CKind.INPUT: ("input", "continuous", None),
    CKind.PARAM_TUNABLE: ("parameter", "tunable", "exact"),
    CKind.PARAM_FIXED: ("parameter", "fixed", "exact"),
    CKind.OUTPUT: ("output", "discrete", "calculated"),
    CKind.STATE: ("local", "discrete", "exact"),
}


def _num(v: float) -> str:
    if not math.isfinite(v):
        raise ValueError(f"modelDescription.xml holds finite numbers only, got {v}")
    return repr(float(v))


def _head(root: ET.Element, ctrl: ControllerModel) -> None:
    units = ET.SubElement(root, "UnitDefinitions")
    for u in sorted({v.unit for v in ctrl.variables if v.unit}):
        ET.SubElement(
            ET.SubElement(units, "Unit", {"name": u}), "BaseUnit", {k: str(e) for k, e in CONTROLLER_UNITS[u].items()}
        )


def _tail(root: ET.Element, ctrl: ControllerModel) -> None:
    cats = ET.SubElement(root, "LogCategories")
    ET.SubElement(
        cats, "Category", {"name": "logStatusError", "description": "errors: bad values, calls in the wrong state"}
    )
    ET.SubElement(cats, "Category", {"name": "logAll", "description": "everything else"})
    stop = max(100 * ctrl.sample_period, 1.0)
    ET.SubElement(
        root, "DefaultExperiment", {"startTime": "0", "stopTime": _num(stop), "stepSize": _num(ctrl.sample_period)}
    )


def _attrs(vr: int, v: CVar) -> dict[str, str]:
    causality, variability, initial = CAUSALITY[v.kind]
    a = {"name": v.name, "valueReference": str(vr), "causality": causality, "variability": variability,
         "description": v.description}  # fmt: skip
    if initial:
        a["initial"] = initial
    return a


def _has_start(v: CVar) -> bool:
    return v.kind not in (CKind.INDEPENDENT, CKind.OUTPUT)


def _deps(ctrl: ControllerModel, name: str, index: dict[str, int]) -> str:
    return " ".join(str(index[i]) for i in ctrl.feedthrough.get(name, []) if i in index)


def fmi3_controller_description(ctrl: ControllerModel, token: str) -> bytes:
    """modelDescription.xml, FMI 3.0, Co-Simulation only."""
    root = root_element(ctrl.name, ctrl.description, token, "3.0")
    ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": ctrl.name, "canHandleVariableCommunicationStepSize": "true", "hasEventMode": "false",
        "canGetAndSetFMUState": "false", "canSerializeFMUState": "false", "providesIntermediateUpdate": "false",
        "canReturnEarlyAfterIntermediateUpdate": "false"})  # fmt: skip
    _head(root, ctrl)
    _tail(root, ctrl)
    mv = ET.SubElement(root, "ModelVariables")
    for vr, v in enumerate(ctrl.variables):
        a = _attrs(vr, v)
        if _has_start(v):
            a["start"] = _num(float(v.start or 0.0))
        if v.unit:
            a["unit"] = v.unit
        ET.SubElement(mv, "Float64", a)
    vrs = {v.name: i for i, v in enumerate(ctrl.variables)}
    ms = ET.SubElement(root, "ModelStructure")
    for tag in ("Output", "InitialUnknown"):
        for v in ctrl.variables:
            if v.kind == CKind.OUTPUT:
                deps = _deps(ctrl, v.name, vrs)
                n = len(deps.split())
                ET.SubElement(ms, tag, {"valueReference": str(vrs[v.name]), "dependencies": deps,
                                        "dependenciesKind": " ".join(["dependent"] * n)})  # fmt: skip
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def fmi2_controller_description(ctrl: ControllerModel, token: str, source_files: list[str]) -> bytes:
    """modelDescription.xml, FMI 2.0, Co-Simulation only (variables referred to by 1-based index)."""
    root = root_element(ctrl.name, ctrl.description, token, "2.0")
    cs = ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": ctrl.name, "canHandleVariableCommunicationStepSize": "true",
        "canGetAndSetFMUstate": "false", "canSerializeFMUstate": "false"})  # fmt: skip
    files = ET.SubElement(cs, "SourceFiles")
    for f in source_files:
        ET.SubElement(files, "File", {"name": f})
    _head(root, ctrl)
    _tail(root, ctrl)
    mv = ET.SubElement(root, "ModelVariables")
    for vr, v in enumerate(ctrl.variables):
        sv = ET.SubElement(mv, "ScalarVariable", _attrs(vr, v))
        real = {}
        if _has_start(v):
            real["start"] = _num(float(v.start or 0.0))
        if v.unit:
            real["unit"] = v.unit
        ET.SubElement(sv, "Real", real)
    index = {v.name: i + 1 for i, v in enumerate(ctrl.variables)}
    ms = ET.SubElement(root, "ModelStructure")
    for tag in ("Outputs", "InitialUnknowns"):
        el = ET.SubElement(ms, tag)
        for v in ctrl.variables:
            if v.kind == CKind.OUTPUT:
                deps = _deps(ctrl, v.name, index)
                kinds = " ".join(["dependent"] * len(deps.split()))
                ET.SubElement(
                    el, "Unknown", {"index": str(index[v.name]), "dependencies": deps, "dependenciesKind": kinds}
                )
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
