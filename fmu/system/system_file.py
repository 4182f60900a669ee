"""A system file (TOML): its components, connections and communication step, read and checked for form.

A system names components (a shipped scene or controller by name, or a path to its file,
relative to the system file; with parameter values), connections ``"A.out -> B.in"`` by
variable name (a vector's base name connects every element: ``"plant.q -> pd.q"`` is
q[1..4]), the communication step
H (s) and the stop time (s). Names and form are checked here, before anything is built;
what needs the components' modelDescription (variables, causality, units, feedthrough) is
checked in `fmu.system.checks` (docs/user_guide.md, "Systems").
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from modelsrc.errors import ModelInputError
from modelsrc.shipped_files import shipped_names, shipped_or_toml

SHIPPED = Path(__file__).parent / "systems"
KINDS = ("scene", "controller")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_ARROW = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\.(\S+)\s*->\s*([A-Za-z_][A-Za-z0-9_]*)\.(\S+)\s*$")


@dataclass(frozen=True)
class Component:
    """One FMU of the system: kind 'scene' or 'controller', source (a shipped name or a file
    path), parameters (variable name -> value, SI units of the FMU's variable)."""

    name: str
    kind: str
    source: str
    parameters: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Connection:
    """Output `start_var` of component `start` drives input `end_var` of `end` (as written;
    a base name is expanded by `fmu.system.checks`)."""

    start: str
    start_var: str
    end: str
    end_var: str

    def __str__(self) -> str:
        return f"{self.start}.{self.start_var} -> {self.end}.{self.end_var}"


@dataclass(frozen=True)
class System:
    """A system file's content: name, components (in file order), connections, the
    communication step H (s), the stop time (s), the file it came from."""

    name: str
    description: str
    components: dict[str, Component]
    connections: list[Connection]
    step: float
    stop_time: float
    path: Path | None = None


def list_systems() -> list[str]:
    """The shipped systems' names (fmu/system/systems/*.toml)."""
    return shipped_names(SHIPPED)


def system_path(name_or_path: str | Path) -> Path:
    """A shipped system's file, or the given .toml path; ModelInputError if neither exists."""
    return shipped_or_toml(name_or_path, SHIPPED, "system")


def _number(value: object, where: str, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ModelInputError(f"{where} = {value!r}: give a finite number")
    if positive and value <= 0:
        raise ModelInputError(f"{where} = {value!r}: must be > 0")
    return float(value)


def _component(name: str, table: object, where: str) -> Component:
    if not _NAME.match(name):
        raise ModelInputError(
            f"{where}: component name {name!r} must be letters, digits and _ (not starting with a digit)"
        )
    if not isinstance(table, dict):
        raise ModelInputError(f"{where}.{name}: must be a table with scene = ... or controller = ...")
    kinds = [k for k in KINDS if k in table]
    if len(kinds) != 1:
        raise ModelInputError(f"{where}.{name}: give exactly one of scene = NAME_OR_FILE, controller = NAME_OR_FILE")
    unknown = set(table) - {*KINDS, "parameters"}
    if unknown:
        raise ModelInputError(
            f"{where}.{name}: unknown key(s) {', '.join(sorted(unknown))} (allowed: scene, controller, parameters)"
        )
    source = table[kinds[0]]
    if not isinstance(source, str) or not source:
        raise ModelInputError(f"{where}.{name}.{kinds[0]}: give a shipped name or a file path")
    params = table.get("parameters", {})
    if not isinstance(params, dict):
        raise ModelInputError(f"{where}.{name}.parameters: must be a table NAME = VALUE")
    values = {str(k): _number(v, f"{where}.{name}.parameters.{k}") for k, v in params.items()}
    return Component(name, kinds[0], source, values)


def _relative(comp: Component, system_file: Path) -> Component:
    """A component whose source is a relative .toml path, made relative to the system file."""
    src = Path(comp.source)
    if comp.source.endswith(".toml") and not src.is_absolute():
        return Component(comp.name, comp.kind, str((system_file.parent / src).resolve()), comp.parameters)
    return comp


def parse_connection(text: object, where: str) -> Connection:
    """'A.out -> B.in' as a Connection; ModelInputError naming the text otherwise."""
    m = _ARROW.match(text) if isinstance(text, str) else None
    if m is None:
        raise ModelInputError(f'{where}: {text!r} is not a connection; write "COMPONENT.OUTPUT -> COMPONENT.INPUT"')
    return Connection(*m.groups())


def read_system(name_or_path: str | Path) -> System:
    """The system of a shipped name or a file, checked for form (components named, keys
    known, numbers finite, connections written A.out -> B.in between named components)."""
    path = system_path(name_or_path)
    try:
        data = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ModelInputError(f"system file {path}: not valid TOML ({exc})") from None
    where = path.name
    unknown = set(data) - {"name", "description", "step", "stop_time", "components", "connections"}
    if unknown:
        raise ModelInputError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}")
    name = data.get("name", path.stem)
    if not isinstance(name, str) or not _NAME.match(name):
        raise ModelInputError(f"{where}: name {name!r} must be letters, digits and _")
    if "step" not in data:
        raise ModelInputError(f"{where}: give the communication step, step = H (s)")
    step = _number(data["step"], f"{where}: step", positive=True)
    stop = _number(data.get("stop_time", 10.0), f"{where}: stop_time", positive=True)
    n = round(stop / step)
    if n < 1 or abs(n * step - stop) > 1e-9 * stop:
        raise ModelInputError(f"{where}: stop_time = {stop} s must be a whole number of communication steps ({step} s)")
    comps_table = data.get("components")
    if not isinstance(comps_table, dict) or not comps_table:
        raise ModelInputError(f"{where}: give at least one component ([components.NAME] with scene = ...)")
    components = {n: _relative(_component(n, t, f"{where}: components"), path) for n, t in comps_table.items()}
    raw = data.get("connections", [])
    if not isinstance(raw, list):
        raise ModelInputError(f'{where}: connections must be a list of "A.out -> B.in" strings')
    connections = [parse_connection(c, f"{where}: connections[{k}]") for k, c in enumerate(raw)]
    for c in connections:
        for comp in (c.start, c.end):
            if comp not in components:
                raise ModelInputError(
                    f"{where}: connection {c}: unknown component {comp!r} (components: {', '.join(components)})"
                )
    return System(name, str(data.get("description", "")), components, connections, step, stop, path)
