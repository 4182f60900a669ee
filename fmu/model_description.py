"""modelDescription.xml and buildDescription.xml (FMI 3.0) from a model's metadata."""
from __future__ import annotations

import xml.etree.ElementTree as ET
from datetime import datetime, timezone

import casadi as ca

from modelsrc.integrators import METHODS
from modelsrc.model import INDEPENDENT, INPUT, OUTPUT, PARAM_FIXED, PARAM_TUNABLE, STATE, RigidBodyModel

VERSION = "0.1.0"

# SI base-unit exponents of every unit the model uses (FMI 3.0 §2.4.3).
UNITS = {
    "s": {"s": 1}, "rad": {"rad": 1}, "rad/s": {"rad": 1, "s": -1},
    "N.m": {"kg": 1, "m": 2, "s": -2}, "kg.m2": {"kg": 1, "m": 2}, "kg": {"kg": 1},
    "m": {"m": 1}, "m/s": {"m": 1, "s": -1}, "m/s2": {"m": 1, "s": -2}, "J": {"kg": 1, "m": 2, "s": -2},
    "N.m.s": {"kg": 1, "m": 2, "s": -1}, "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
}

_CAUSALITY = {
    INDEPENDENT: ("independent", "continuous", None),
    STATE: ("output", "continuous", "exact"),
    INPUT: ("input", "continuous", None),
    PARAM_FIXED: ("parameter", "fixed", "exact"),
    PARAM_TUNABLE: ("parameter", "tunable", "exact"),
    OUTPUT: ("output", "continuous", "calculated"),
}


def _fmt(v: float) -> str:
    return repr(float(v))


def model_description_xml(model: RigidBodyModel, token: str) -> bytes:
    """The modelDescription.xml of a scene's Co-Simulation FMU."""
    sc = model.scene
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": sc.name, "instantiationToken": token,
        "description": sc.description,
        "generationTool": f"rbfmu {VERSION} (CasADi {ca.__version__})",
        "generationDateAndTime": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "variableNamingConvention": "structured",
    })
    ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": sc.name, "canHandleVariableCommunicationStepSize": "true",
        "canGetAndSetFMUState": "false", "canSerializeFMUState": "false",
        "providesDirectionalDerivatives": "false", "providesAdjointDerivatives": "false",
        "hasEventMode": "false", "canReturnEarlyAfterIntermediateUpdate": "false",
    })
    used = sorted({v.unit for v in model.variables if v.unit})
    units = ET.SubElement(root, "UnitDefinitions")
    for u in used:
        el = ET.SubElement(units, "Unit", {"name": u})
        ET.SubElement(el, "BaseUnit", {k: str(e) for k, e in UNITS[u].items()})
    types = ET.SubElement(root, "TypeDefinitions")
    et = ET.SubElement(types, "EnumerationType", {"name": "Method", "description": "integrator inside the FMU"})
    for m in model.methods:
        ET.SubElement(et, "Item", {"name": m, "value": str(METHODS[m][0]), "description": METHODS[m][1]})
    cats = ET.SubElement(root, "LogCategories")
    ET.SubElement(cats, "Category", {"name": "logStatusError",
                                     "description": "errors: bad values, calls in the wrong state"})
    ET.SubElement(root, "DefaultExperiment", {"startTime": "0", "stopTime": _fmt(sc.stop_time),
                                              "stepSize": _fmt(sc.step)})
    mv = ET.SubElement(root, "ModelVariables")
    for vr, v in enumerate(model.variables):
        causality, variability, initial = _CAUSALITY[v.kind]
        attrs = {"name": v.name, "valueReference": str(vr), "causality": causality,
                 "variability": variability, "description": v.description}
        if initial:
            attrs["initial"] = initial
        if v.start is not None and v.kind != INDEPENDENT and initial != "calculated":
            attrs["start"] = _fmt(v.start)
        if v.unit:
            attrs["unit"] = v.unit
        ET.SubElement(mv, "Float64", attrs)
    ET.SubElement(mv, "Enumeration", {
        "name": "method", "valueReference": str(len(model.variables)), "declaredType": "Method",
        "causality": "parameter", "variability": "tunable", "start": str(METHODS[model.default_method][0]),
        "description": "integrator used inside doStep (see the Method type)"})
    ms = ET.SubElement(root, "ModelStructure")
    for vr, v in enumerate(model.variables):
        if v.kind in (STATE, OUTPUT):
            ET.SubElement(ms, "Output", {"valueReference": str(vr)})
    for vr, v in enumerate(model.variables):
        if v.kind == OUTPUT:
            ET.SubElement(ms, "InitialUnknown", {"valueReference": str(vr)})
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def build_description_xml(model_identifier: str, sources: list[str]) -> bytes:
    """buildDescription.xml: how to rebuild the binary from sources/ on another platform."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    cfg = ET.SubElement(root, "BuildConfiguration", {"modelIdentifier": model_identifier})
    fs = ET.SubElement(cfg, "SourceFileSet", {"language": "C99"})
    for s in sources:
        ET.SubElement(fs, "SourceFile", {"name": s})
    ET.SubElement(cfg, "Library", {"name": "m"})
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
