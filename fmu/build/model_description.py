"""Writes modelDescription.xml (FMI 3.0 or 2.0, CS and ME in one FMU) and buildDescription.xml from the metadata."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from datetime import UTC, datetime

import casadi as ca

from modelsrc.errors import ModelInputError
from modelsrc.methods import METHODS
from modelsrc.model import RigidBodyModel
from modelsrc.variables import Kind

from .. import __version__
from .licensing import COPYRIGHT, license_attribute
from .model_data import MAX_OUTPUT_ORDER

VERSION = __version__  # the FMU's `version` attribute: the package's (CHANGELOG.md)

# SI base-unit exponents of every unit the model uses (FMI 3.0 §2.4.3, FMI 2.0 §2.2.2).
UNITS = {
    "s": {"s": 1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
    "1/s": {"s": -1},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "kg.m2": {"kg": 1, "m": 2},
    "kg": {"kg": 1},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "m3/s2": {"m": 3, "s": -2},  # a gravitational parameter G M (docs/theory.md §9.7)
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.s": {"kg": 1, "m": 1, "s": -1},
    "J": {"kg": 1, "m": 2, "s": -2},
    "N.m.s": {"kg": 1, "m": 2, "s": -1},
    "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
}

# kind -> (causality, variability, initial)
CAUSALITY = {
    Kind.INDEPENDENT: ("independent", "continuous", None),
    Kind.STATE: ("output", "continuous", "exact"),
    Kind.INPUT: ("input", "continuous", None),
    Kind.PARAM_FIXED: ("parameter", "fixed", "exact"),
    Kind.PARAM_TUNABLE: ("parameter", "tunable", "exact"),
    Kind.OUTPUT: ("output", "continuous", "calculated"),
    Kind.DERIVATIVE: ("local", "continuous", "calculated"),
    Kind.LOCAL: ("local", "discrete", "calculated"),  # the step report, changed by doStep only
}

CAPABILITIES = {
    "canGetAndSetFMUState": "true",
    "canSerializeFMUState": "true",
    "providesDirectionalDerivatives": "true",
    "providesAdjointDerivatives": "true",
}


def _fmt(v: float | None) -> str:
    if v is None:
        raise ValueError("a start value is needed here")
    if not math.isfinite(v):  # check_attribute_values names the variable before anything is written
        raise ModelInputError(f"modelDescription.xml holds finite numbers only, got {v}")
    return repr(float(v))


def check_attribute_values(model: RigidBodyModel) -> None:
    """ModelInputError naming the variable unless every number the model description
    will carry is valid: start values finite (xs:double, and the C code's literals),
    nominals finite and > 0 (the FMI standard's rule for nominal), the experiment's times
    finite and > 0. Called before any file of the build is written."""
    sc = model.scene
    for what, value in (("experiment.stop_time", sc.stop_time), ("experiment.step", sc.step)):
        if not (math.isfinite(value) and value > 0):
            raise ModelInputError(f"scene {sc.name}: {what} = {value} must be finite and > 0")
    for v in model.variables:
        start = v.start if _attrs(0, v)[2] else None
        if start is not None and not math.isfinite(start):
            raise ModelInputError(
                f"scene {sc.name}: variable {v.name}: start value {start} is not finite (the scene's values "
                "overflow double precision); modelDescription.xml and the C code hold finite numbers only"
            )
        if v.nominal is not None and not (math.isfinite(v.nominal) and v.nominal > 0):
            raise ModelInputError(
                f"scene {sc.name}: variable {v.name}: nominal {v.nominal} must be finite and > 0 (the scene's "
                "values overflow double precision)"
            )


def root_element(name: str, description: str, token: str, version: str) -> ET.Element:
    """The fmiModelDescription element of every rbfmu FMU (a scene's, a controller's): its
    name, description, the package's version, copyright, licence, generation tool and time,
    and the instantiation token (FMI 3.0, `version` "3.0") or guid and no event indicators
    (FMI 2.0); the attributes in this order (the written XML keeps it)."""
    attrs = {
        "fmiVersion": version,
        "modelName": name,
        "description": description,
        "version": VERSION,
        "copyright": COPYRIGHT,
        "license": license_attribute(version[0]),
        "generationTool": f"rbfmu {VERSION} (CasADi {ca.__version__})",  # type: ignore[attr-defined]
        "generationDateAndTime": datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "variableNamingConvention": "structured",
    }
    if version == "3.0":
        attrs["instantiationToken"] = token
    else:
        attrs["guid"] = token
        attrs["numberOfEventIndicators"] = "0"
    return ET.Element("fmiModelDescription", attrs)


def _units(root: ET.Element, model: RigidBodyModel) -> None:
    units = ET.SubElement(root, "UnitDefinitions")
    for u in sorted({v.unit for v in model.variables if v.unit}):
        el = ET.SubElement(units, "Unit", {"name": u})
        ET.SubElement(el, "BaseUnit", {k: str(e) for k, e in UNITS[u].items()})


def _tail(root: ET.Element, model: RigidBodyModel) -> None:
    cats = ET.SubElement(root, "LogCategories")
    ET.SubElement(
        cats, "Category", {"name": "logStatusError", "description": "errors: bad values, calls in the wrong state"}
    )
    ET.SubElement(
        cats,
        "Category",
        {"name": "logStatusWarning", "description": "settings not applied as given (the importer's tolerance, a "
         "tolerance below what the error estimate resolves)"},
    )  # fmt: skip
    ET.SubElement(cats, "Category", {"name": "logAll", "description": "everything else"})
    sc = model.scene
    experiment = {"startTime": "0", "stopTime": _fmt(sc.stop_time), "stepSize": _fmt(sc.step)}
    # the scene's tolerance, which an importer passes back (fmpy does): the same error control
    # either way (docs/fmi_layer.md, Tolerance); none for a scene of fixed steps (tolerance 0),
    # where an importer's relative tolerance would mean nothing
    if sc.tolerance > 0:
        experiment["tolerance"] = _fmt(sc.tolerance)
    ET.SubElement(root, "DefaultExperiment", experiment)


def _attrs(vr: int, v) -> tuple[dict, str | None, bool]:
    causality, variability, initial = CAUSALITY[v.kind]
    attrs = {
        "name": v.name,
        "valueReference": str(vr),
        "causality": causality,
        "variability": variability,
        "description": v.description,
    }
    if initial and v.kind != Kind.DERIVATIVE:
        attrs["initial"] = initial
    has_start = v.start is not None and v.kind not in (Kind.INDEPENDENT, Kind.OUTPUT, Kind.DERIVATIVE, Kind.LOCAL)
    return attrs, initial, has_start


def fmi3_model_description(model: RigidBodyModel, token: str, source_files: Sequence[str] = ()) -> bytes:
    """modelDescription.xml, FMI 3.0, with Model Exchange and Co-Simulation. The source
    files are listed in sources/buildDescription.xml instead (FMI 3.0 §2.5.2)."""
    sc = model.scene
    root = root_element(model.scene.name, model.scene.description, token, "3.0")
    ET.SubElement(
        root, "ModelExchange", {"modelIdentifier": sc.name, "needsCompletedIntegratorStep": "false", **CAPABILITIES}
    )
    ET.SubElement(
        root,
        "CoSimulation",
        {
            "modelIdentifier": sc.name,
            "canHandleVariableCommunicationStepSize": "true",
            "hasEventMode": "false",
            "maxOutputDerivativeOrder": str(MAX_OUTPUT_ORDER),
            "providesIntermediateUpdate": "true",
            "canReturnEarlyAfterIntermediateUpdate": "false",
            **CAPABILITIES,
        },
    )
    _units(root, model)
    types = ET.SubElement(root, "TypeDefinitions")
    et = ET.SubElement(types, "EnumerationType", {"name": "Method", "description": "integrator inside the FMU"})
    for m in model.methods:
        ET.SubElement(et, "Item", {"name": m, "value": str(METHODS[m].value), "description": METHODS[m].description})
    _tail(root, model)
    mv = ET.SubElement(root, "ModelVariables")
    for vr, v in enumerate(model.variables):
        attrs, _, has_start = _attrs(vr, v)
        if has_start:
            attrs["start"] = _fmt(v.start)
        if v.unit:
            attrs["unit"] = v.unit
        if v.nominal is not None:
            attrs["nominal"] = _fmt(v.nominal)
        if v.derivative_of is not None:
            attrs["derivative"] = str(v.derivative_of)  # FMI 3.0: the state's value reference
        if v.kind == Kind.INPUT:  # settable at the FMU's internal step points (intermediate update)
            attrs["intermediateUpdate"] = "true"
        ET.SubElement(mv, "Float64", attrs)
    ET.SubElement(
        mv,
        "Enumeration",
        {
            "name": "method",
            "valueReference": str(len(model.variables)),
            "declaredType": "Method",
            "causality": "parameter",
            "variability": "tunable",
            "start": str(METHODS[model.default_method].value),
            "description": "integrator used inside doStep (see the Method type)",
        },
    )
    ms = ET.SubElement(root, "ModelStructure")
    for vr, v in enumerate(model.variables):
        if v.kind in (Kind.STATE, Kind.OUTPUT):
            ET.SubElement(ms, "Output", {"valueReference": str(vr)})
    for vr, v in enumerate(model.variables):
        if v.kind == Kind.DERIVATIVE:
            ET.SubElement(ms, "ContinuousStateDerivative", {"valueReference": str(vr)})
    for vr, v in enumerate(model.variables):
        if v.kind in (Kind.OUTPUT, Kind.DERIVATIVE):
            ET.SubElement(ms, "InitialUnknown", {"valueReference": str(vr)})
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def fmi2_model_description(model: RigidBodyModel, token: str, source_files: Sequence[str] = ()) -> bytes:
    """modelDescription.xml, FMI 2.0, with Model Exchange and Co-Simulation. The method
    enumeration's values are the documented integers of modelsrc.methods.METHODS;
    source_files (in sources/) are listed in both interfaces' SourceFiles (FMI 2.0 §3.3, §4.3.1)."""
    sc = model.scene
    root = root_element(model.scene.name, model.scene.description, token, "2.0")
    caps = {"canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true", "providesDirectionalDerivative": "true"}
    me = ET.SubElement(
        root, "ModelExchange", {"modelIdentifier": sc.name, "completedIntegratorStepNotNeeded": "true", **caps}
    )
    cs = ET.SubElement(
        root,
        "CoSimulation",
        {
            "modelIdentifier": sc.name,
            "canHandleVariableCommunicationStepSize": "true",
            "canInterpolateInputs": "true",
            "maxOutputDerivativeOrder": str(MAX_OUTPUT_ORDER),
            **caps,
        },
    )
    for interface in (me, cs):
        if source_files:
            files = ET.SubElement(interface, "SourceFiles")
            for f in source_files:
                ET.SubElement(files, "File", {"name": f})
    _units(root, model)
    types = ET.SubElement(root, "TypeDefinitions")
    st = ET.SubElement(types, "SimpleType", {"name": "Method", "description": "integrator inside the FMU"})
    en = ET.SubElement(st, "Enumeration")
    for m in model.methods:
        ET.SubElement(en, "Item", {"name": m, "value": str(METHODS[m].value), "description": METHODS[m].description})
    _tail(root, model)
    mv = ET.SubElement(root, "ModelVariables")
    index: dict[int, int] = {}  # value reference -> 1-based position in ModelVariables (FMI 2.0 refers by index)
    for vr, v in enumerate(model.variables):
        attrs, _, has_start = _attrs(vr, v)
        if v.kind == Kind.INDEPENDENT:
            attrs.pop("initial", None)
        index[vr] = len(index) + 1
        sv = ET.SubElement(mv, "ScalarVariable", attrs)
        real = {}
        if has_start:
            real["start"] = _fmt(v.start)
        if v.unit:
            real["unit"] = v.unit
        if v.nominal is not None:
            real["nominal"] = _fmt(v.nominal)
        if v.derivative_of is not None:
            real["derivative"] = str(index[v.derivative_of])
        ET.SubElement(sv, "Real", real)
    sv = ET.SubElement(
        mv,
        "ScalarVariable",
        {
            "name": "method",
            "valueReference": str(len(model.variables)),
            "causality": "parameter",
            "variability": "tunable",
            "initial": "exact",
            "description": "integrator used inside doStep (values: see the Method type)",
        },
    )
    ET.SubElement(sv, "Enumeration", {"declaredType": "Method", "start": str(METHODS[model.default_method].value)})
    ms = ET.SubElement(root, "ModelStructure")
    outs = ET.SubElement(ms, "Outputs")
    for vr, v in enumerate(model.variables):
        if v.kind in (Kind.STATE, Kind.OUTPUT):
            ET.SubElement(outs, "Unknown", {"index": str(index[vr])})
    ders = ET.SubElement(ms, "Derivatives")
    for vr, v in enumerate(model.variables):
        if v.kind == Kind.DERIVATIVE:
            ET.SubElement(ders, "Unknown", {"index": str(index[vr])})
    inits = ET.SubElement(ms, "InitialUnknowns")
    for vr, v in enumerate(model.variables):
        if v.kind in (Kind.OUTPUT, Kind.DERIVATIVE):
            ET.SubElement(inits, "Unknown", {"index": str(index[vr])})
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


# The shipped binaries' options (fmu.build.compile.CFLAGS) for gcc and clang. The sources already
# carry the two that change the binary's behaviour (fmu/c/rbfmu_build.h): any compiler
# without options builds the same library.
SOURCE_COMPILER_OPTIONS = "-O2 -ffp-contract=off -fvisibility=hidden"
BUILD_NOTE = (
    "One shared library of all the C files, linked with libm. The sources hide every symbol but the "
    "fmi* functions and turn floating-point contraction off themselves (rbfmu_build.h), so no option "
    "is required; compilerOptions are the shipped binaries' (gcc, clang). -ffast-math is refused."
)


def build_description_xml(model_identifier: str, sources: list[str], version: str = "3.0") -> bytes:
    """buildDescription.xml: how to rebuild the binary from sources/ on another platform."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": version})
    cfg = ET.SubElement(root, "BuildConfiguration", {"modelIdentifier": model_identifier,
                        "description": BUILD_NOTE})  # fmt: skip
    fs = ET.SubElement(cfg, "SourceFileSet", {"language": "C99", "compilerOptions": SOURCE_COMPILER_OPTIONS})
    for s in sources:
        ET.SubElement(fs, "SourceFile", {"name": s})
    ET.SubElement(cfg, "Library", {"name": "m"})
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
