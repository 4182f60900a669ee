"""An .ssp archive opened for a run: checked to be one (one-line refusals), and what the run reads from its SSD.

`open_archive` refuses a missing file, a file that is no zip, a zip without
SystemStructure.ssd, an SSD that is not XML or names an FMU the archive lacks, and an SSD
without the communication step (rbfmu's annotation, fmu.system.ssp) — each as one line
naming the file.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from modelsrc.errors import ModelInputError

from .ssp import PARAMETER_SET, RBFMU, SSC, SSD, SSD_MEMBER


@dataclass(frozen=True)
class SystemArchive:
    """An opened archive: its path, the system's name, H (s), the stop time (s), the
    'component.variable' names of every Real input and output connector (SSD order), and
    the parameter set to apply (None: the archive has no parameter values), the
    'component.variable' names of the connections' sources (the outputs that drive inputs),
    and the connectors' units (the SSD's ssc:Real unit, where it has one)."""

    path: Path
    name: str
    step: float
    stop_time: float
    variables: list[str]
    parameter_set_name: str | None
    sources: list[str]
    units: dict[str, str] = field(default_factory=dict)


def open_archive(path: str | Path) -> SystemArchive:
    """The archive at `path`, or a ModelInputError of one line naming it and what is wrong."""
    p = Path(path)
    if not p.is_file():
        raise ModelInputError(f"{p}: no such archive (build one with `rbfmu system build SYSTEM`)")
    try:
        with zipfile.ZipFile(p) as z:
            members = set(z.namelist())
            if SSD_MEMBER not in members:
                raise ModelInputError(f"{p}: not an SSP archive (no {SSD_MEMBER} inside)")
            root = ET.fromstring(z.read(SSD_MEMBER))
    except zipfile.BadZipFile:
        raise ModelInputError(f"{p}: not an SSP archive (not a zip file, or a damaged one)") from None
    except ET.ParseError as exc:
        raise ModelInputError(f"{p}: {SSD_MEMBER} is not valid XML ({exc})") from None
    except (OSError, zipfile.LargeZipFile, RuntimeError) as exc:  # unreadable, encrypted, damaged member
        raise ModelInputError(f"{p}: cannot be read as an SSP archive ({exc})") from None
    system = root.find(f"{{{SSD}}}System")
    if root.tag != f"{{{SSD}}}SystemStructureDescription" or system is None:
        raise ModelInputError(f"{p}: {SSD_MEMBER} is not an SSP 1.0 SystemStructureDescription")
    names, units, bound = [], {}, False
    for comp in system.iter(f"{{{SSD}}}Component"):
        src = comp.get("source", "")
        if src not in members:
            raise ModelInputError(f"{p}: component {comp.get('name')} names {src!r}, which the archive lacks")
        bound = bound or comp.find(f"{{{SSD}}}ParameterBindings") is not None
        for con in comp.iter(f"{{{SSD}}}Connector"):
            real = con.find(f"{{{SSC}}}Real")
            if con.get("kind") in ("input", "output") and real is not None:
                names.append(f"{comp.get('name')}.{con.get('name')}")
                if real.get("unit"):
                    units[names[-1]] = real.get("unit", "")
    sources: list[str] = []
    for con in system.iter(f"{{{SSD}}}Connection"):
        name = f"{con.get('startElement')}.{con.get('startConnector')}"
        if name in names and name not in sources:
            sources.append(name)
    step_el = root.find(f"{{{SSD}}}Annotations/{{{SSC}}}Annotation[@type='{RBFMU}']/CommunicationStep")
    exp = root.find(f"{{{SSD}}}DefaultExperiment")
    try:
        step = float(step_el.get("value", "")) if step_el is not None else None
        stop = float(exp.get("stopTime", "")) if exp is not None else None
    except ValueError:
        step = stop = None
    if step is None or stop is None or not 0 < step < math.inf or not stop > 0:
        raise ModelInputError(f"{p}: its SSD lacks the communication step or the stop time (not built by rbfmu?)")
    return SystemArchive(
        p, root.get("name", p.stem), step, stop, names, PARAMETER_SET if bound else None, sources, units
    )
