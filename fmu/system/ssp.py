"""SSP 1.0 archives: SystemStructure.ssd, the components' FMUs under resources/, their parameter values as .ssv.

The .ssp is a zip (SSP 1.0, §3): SystemStructure.ssd at its root names each component
(source resources/COMPONENT.fmu), its connectors (inputs, outputs and the parameters it
sets, typed ssc:Real with the FMU's unit), a ParameterBinding to resources/COMPONENT.ssv
where it has parameter values, and the connections in the system file's order. The SSD's
DefaultExperiment carries the stop time; the communication step is an annotation
(SSP 1.0 has no attribute for it) that `rbfmu system run` reads back. Every FMU in the
archive is FMI 2.0 Co-Simulation: libcosim runs FMI 2.0 only, and ECOS's FMI 3.0 support
lacks fmi3GetVersion and enumerations (docs/user_guide.md, "Systems").
"""

from __future__ import annotations

import shutil
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from .checks import Link
from .interface import Interface
from .system_file import System

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
RBFMU = "org.rbfmu.system"  # the annotation type of rbfmu's own facts (communication step)
SSD_MEMBER = "SystemStructure.ssd"
PARAMETER_SET = "parameters"  # the name of every component's ssv:ParameterSet (ECOS applies a named set)

ET.register_namespace("ssd", SSD)
ET.register_namespace("ssc", SSC)
ET.register_namespace("ssv", SSV)


def _q(ns: str, tag: str) -> str:
    return f"{{{ns}}}{tag}"


def _num(x: float) -> str:
    return repr(float(x))


def _unit_table(fmus: dict[str, Path]) -> dict[str, dict[str, str]]:
    """Unit name -> BaseUnit attributes, read from the FMUs' UnitDefinitions."""
    units: dict[str, dict[str, str]] = {}
    for fmu in fmus.values():
        with zipfile.ZipFile(fmu) as z:
            root = ET.fromstring(z.read("modelDescription.xml"))
        for u in root.iter("Unit"):
            base = u.find("BaseUnit")
            units[u.get("name", "")] = dict(base.attrib) if base is not None else {}
    return units


def _connector(parent: ET.Element, name: str, kind: str, unit: str) -> None:
    c = ET.SubElement(parent, _q(SSD, "Connector"), {"name": name, "kind": kind})
    ET.SubElement(c, _q(SSC, "Real"), {"unit": unit} if unit else {})


def ssd_xml(system: System, interfaces: dict[str, Interface], links: list[Link], fmus: dict[str, Path]) -> bytes:
    """SystemStructure.ssd of the system (module docstring)."""
    root = ET.Element(_q(SSD, "SystemStructureDescription"), {"version": "1.0", "name": system.name})
    sys_el = ET.SubElement(root, _q(SSD, "System"), {"name": system.name, "description": system.description})
    elements = ET.SubElement(sys_el, _q(SSD, "Elements"))
    used_units: set[str] = set()
    for comp in system.components.values():
        iface = interfaces[comp.name]
        el = ET.SubElement(
            elements,
            _q(SSD, "Component"),
            {"name": comp.name, "type": "application/x-fmu-sharedlibrary", "source": f"resources/{comp.name}.fmu"},
        )
        cons = ET.SubElement(el, _q(SSD, "Connectors"))
        for kind in ("input", "output"):
            for n in iface.names(kind):
                if iface.ports[n].type == "Real":
                    _connector(cons, n, kind, iface.ports[n].unit)
                    used_units.add(iface.ports[n].unit)
        for n in comp.parameters:
            if iface.ports[n].causality == "parameter":
                _connector(cons, n, "parameter", iface.ports[n].unit)
                used_units.add(iface.ports[n].unit)
        if comp.parameters:
            binds = ET.SubElement(el, _q(SSD, "ParameterBindings"))
            ET.SubElement(
                binds,
                _q(SSD, "ParameterBinding"),
                {"type": "application/x-ssp-parameter-set", "source": f"resources/{comp.name}.ssv"},
            )
    if links:  # SSP 1.0: Connections, when present, holds at least one
        conns = ET.SubElement(sys_el, _q(SSD, "Connections"))
        for link in links:
            ET.SubElement(
                conns,
                _q(SSD, "Connection"),
                {"startElement": link.start, "startConnector": link.start_var, "endElement": link.end,
                 "endConnector": link.end_var},
            )  # fmt: skip
    table = _unit_table(fmus)
    used_units.discard("")
    if used_units:
        units = ET.SubElement(root, _q(SSD, "Units"))
        for u in sorted(used_units):
            ET.SubElement(ET.SubElement(units, _q(SSC, "Unit"), {"name": u}), _q(SSC, "BaseUnit"), table.get(u, {}))
    ET.SubElement(root, _q(SSD, "DefaultExperiment"), {"startTime": "0", "stopTime": _num(system.stop_time)})
    ann = ET.SubElement(ET.SubElement(root, _q(SSD, "Annotations")), _q(SSC, "Annotation"), {"type": RBFMU})
    ET.SubElement(ann, "CommunicationStep", {"value": _num(system.step), "unit": "s"})
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def ssv_xml(values: dict[str, float], interface: Interface, unit_table: dict[str, dict[str, str]]) -> bytes:
    """A component's parameter values as an ssv:ParameterSet named PARAMETER_SET (units with
    their SI base units from `unit_table`, as `_unit_table` reads them)."""
    root = ET.Element(_q(SSV, "ParameterSet"), {"version": "1.0", "name": PARAMETER_SET})
    params = ET.SubElement(root, _q(SSV, "Parameters"))
    for n, v in values.items():
        p = ET.SubElement(params, _q(SSV, "Parameter"), {"name": n})
        unit = interface.ports[n].unit
        ET.SubElement(p, _q(SSV, "Real"), {"value": _num(v), **({"unit": unit} if unit else {})})
    if any(interface.ports[n].unit for n in values):
        units = ET.SubElement(root, _q(SSV, "Units"))
        for u in sorted({interface.ports[n].unit for n in values} - {""}):
            ET.SubElement(
                ET.SubElement(units, _q(SSC, "Unit"), {"name": u}), _q(SSC, "BaseUnit"), unit_table.get(u, {})
            )
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def write_ssp(
    system: System, interfaces: dict[str, Interface], links: list[Link], fmus: dict[str, Path], path: Path
) -> Path:
    """Write the archive to `path` (through a temporary file: a failed write leaves none)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile(dir=path.parent, suffix=".ssp.part", delete=False) as f:
        tmp = Path(f.name)
    try:
        table = _unit_table(fmus)
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr(SSD_MEMBER, ssd_xml(system, interfaces, links, fmus))
            for comp in system.components.values():
                z.write(fmus[comp.name], f"resources/{comp.name}.fmu")
                if comp.parameters:
                    z.writestr(f"resources/{comp.name}.ssv", ssv_xml(comp.parameters, interfaces[comp.name], table))
        shutil.move(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path
