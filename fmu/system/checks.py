"""The checks of a system against its components' interfaces: each refusal names the connection or component.

Run by `rbfmu system build` after the components' FMUs exist and before the archive is
written, so a refused system writes no archive. Refused: an unknown component or variable,
a connection that does not start at an output or does not end at an input, two sources for
one input, a unit mismatch (the units' names in the modelDescriptions differ), a
parameter that is no parameter or input of its component or is on an input a connection
drives (the connection would overwrite it every step), a communication step H the
controller's sample period Ts is not a multiple of (the controller samples every m-th
communication point, Ts = m·H, m a whole number; docs/user_guide.md, "Systems"), a loop of
direct feedthrough (an algebraic loop: no master can order its evaluations), and a
controller with more outputs than its plant has inputs it could drive. A parameter value
almost surely given in the wrong unit is warned about (`warn_unit_mistakes`), not refused.
"""

from __future__ import annotations

from dataclasses import dataclass

from modelsrc import unit_mistakes
from modelsrc.errors import ModelInputError

from .interface import Interface
from .system_file import Connection, System

# the controller variable that holds its sample period (s)
SAMPLE_PERIOD_NAMES = ("sample_period", "Ts")
# Ts / H within this of a whole number counts as one (decimal steps such as 0.1 are not exact in binary)
MULTIPLE_TOL = 1e-9


@dataclass(frozen=True)
class Link:
    """One scalar connection: output start.start_var drives input end.end_var; `written`
    is the system file's connection it came from."""

    start: str
    start_var: str
    end: str
    end_var: str
    written: Connection

    def __str__(self) -> str:
        return f"{self.start}.{self.start_var} -> {self.end}.{self.end_var}"


def _elements(iface: Interface, var: str) -> list[str] | None:
    """[var] for a scalar variable, [var[1], …, var[n]] for a vector's base name, else None."""
    if var in iface.ports:
        return [var]
    elems: list[str] = []
    while f"{var}[{len(elems) + 1}]" in iface.ports:
        elems.append(f"{var}[{len(elems) + 1}]")
    return elems or None


def _variable(iface: Interface, comp: str, var: str, c: Connection, causality: str) -> list[str]:
    elems = _elements(iface, var)
    if elems is None:
        have = ", ".join(sorted({n.split("[")[0] for n in iface.names(causality)})) or "none"
        raise ModelInputError(f"connection {c}: component {comp} has no variable {var!r} ({causality}s: {have})")
    for e in elems:
        got = iface.ports[e].causality
        if got != causality:
            role = "start at an output" if causality == "output" else "end at an input"
            raise ModelInputError(f"connection {c}: {comp}.{e} is an {got}, but a connection must {role}")
    return elems


def expand(system: System, interfaces: dict[str, Interface]) -> list[Link]:
    """The system's connections as scalar links, each checked: both ends exist, the start is
    an output, the end an input, a vector has as many elements at both ends."""
    links = []
    for c in system.connections:
        outs = _variable(interfaces[c.start], c.start, c.start_var, c, "output")
        ins = _variable(interfaces[c.end], c.end, c.end_var, c, "input")
        if len(outs) != len(ins):
            raise ModelInputError(f"connection {c}: {len(outs)} output element(s) into {len(ins)} input element(s)")
        links += [Link(c.start, o, c.end, i, c) for o, i in zip(outs, ins)]
    return links


def check_sources(links: list[Link]) -> None:
    """At most one source per input."""
    seen: dict[tuple[str, str], Link] = {}
    for link in links:
        key = (link.end, link.end_var)
        if key in seen:
            raise ModelInputError(f"input {link.end}.{link.end_var} has two sources: {seen[key]} and {link}")
        seen[key] = link


def check_units(links: list[Link], interfaces: dict[str, Interface]) -> None:
    """The unit of the output equals the unit of the input (by their names in the modelDescriptions)."""
    for link in links:
        a = interfaces[link.start].ports[link.start_var].unit or "no unit"
        b = interfaces[link.end].ports[link.end_var].unit or "no unit"
        if a != b:
            raise ModelInputError(f"connection {link}: unit mismatch, {a} into {b}")


def check_parameters(system: System, interfaces: dict[str, Interface], links: list[Link]) -> None:
    """Every parameter value names a Real parameter or input of its component, and no input
    a connection drives (the master writes the connection's value to it every step: the
    parameter's value would never be seen)."""
    driven = {(lk.end, lk.end_var): lk for lk in links}
    for comp in system.components.values():
        iface = interfaces[comp.name]
        for name in comp.parameters:
            port = iface.ports.get(name)
            if port is None or port.causality not in ("parameter", "input") or port.type != "Real":
                allowed = ", ".join(n for n in iface.names("parameter") if iface.ports[n].type == "Real")
                raise ModelInputError(
                    f"component {comp.name}: {name!r} is not a Real parameter or input of its FMU "
                    f"(parameters: {allowed})"
                )
            link = driven.get((comp.name, name))
            if link is not None:
                via = f"connection {link.written}" + (f" ({link})" if str(link) != str(link.written) else "")
                raise ModelInputError(
                    f"component {comp.name}: parameter {name} = {comp.parameters[name]:g} is on an input that "
                    f"{via} drives: the connection sets it every step, so the value would be ignored; remove "
                    "the parameter or the connection"
                )


def warn_unit_mistakes(system: System) -> None:
    """Warn for each parameter value of the system file almost surely given in the wrong unit
    (modelsrc.unit_mistakes.start_value, the check of `rbfmu run --set`: n_orbit, orbit_angle)."""
    where = system.path.name if system.path is not None else system.name
    for comp in system.components.values():
        for name, value in comp.parameters.items():
            unit_mistakes.start_value(f"{where}: components.{comp.name}.parameters.{name}", name, value)


def sample_period(system: System, interfaces: dict[str, Interface], comp: str) -> float | None:
    """The controller's sample period Ts (s): its parameter value in the system file, else its
    FMU's start value; None when the FMU has no such variable."""
    for name in SAMPLE_PERIOD_NAMES:
        if name in system.components[comp].parameters:
            return system.components[comp].parameters[name]
        port = interfaces[comp].ports.get(name)
        if port is not None and port.start is not None:
            return port.start
    return None


def check_sample_periods(system: System, interfaces: dict[str, Interface]) -> None:
    """Each controller's Ts is a whole multiple m ≥ 1 of the communication step H."""
    for comp in system.components.values():
        if comp.kind != "controller":
            continue
        ts = sample_period(system, interfaces, comp.name)
        if ts is None:
            continue
        m = ts / system.step
        if round(m) < 1 or abs(m - round(m)) > MULTIPLE_TOL * max(1.0, m):
            raise ModelInputError(
                f"component {comp.name}: its sample period Ts = {ts:g} s is not a whole multiple of the "
                f"communication step H = {system.step:g} s (it samples every m-th communication point, Ts = m·H)"
            )


def check_feedthrough_loops(links: list[Link], interfaces: dict[str, Interface]) -> None:
    """No cycle of links and direct feedthrough (output depends on an input at the same instant)."""
    graph: dict[tuple[str, str], list[tuple[tuple[str, str], Link | None]]] = {}
    for link in links:
        graph.setdefault((link.start, link.start_var), []).append(((link.end, link.end_var), link))
    for comp, iface in interfaces.items():
        for out, ins in iface.feedthrough.items():
            for i in ins:
                graph.setdefault((comp, i), []).append(((comp, out), None))
    state: dict[tuple[str, str], int] = {}  # 1: on the current path, 2: done
    nodes: list[tuple[str, str]] = []  # the current path
    edges: list[Link | None] = []  # edges[k] leads from nodes[k] to nodes[k + 1]

    def visit(node: tuple[str, str]) -> None:
        state[node] = 1
        nodes.append(node)
        for nxt, link in graph.get(node, []):
            if state.get(nxt) == 1:
                cycle = [str(lk) for lk in [*edges[nodes.index(nxt) :], link] if lk is not None]
                raise ModelInputError(
                    f"a loop of direct feedthrough (an algebraic loop): {'; '.join(cycle)}; every output on it "
                    "depends on its component's input at the same instant"
                )
            if state.get(nxt) is None:
                edges.append(link)
                visit(nxt)
                edges.pop()
        nodes.pop()
        state[node] = 2

    for node in list(graph):
        if state.get(node) is None:
            visit(node)


def check_controller_outputs(system: System, links: list[Link], interfaces: dict[str, Interface]) -> None:
    """A controller has no more Real outputs than its plants (the scenes it drives, or every
    scene when it drives none) have Real inputs."""
    scenes = [c.name for c in system.components.values() if c.kind == "scene"]
    for comp in system.components.values():
        if comp.kind != "controller":
            continue
        outs = [n for n in interfaces[comp.name].names("output") if interfaces[comp.name].ports[n].type == "Real"]
        plants = sorted({lk.end for lk in links if lk.start == comp.name and lk.end in scenes}) or scenes
        ins = [
            f"{p}.{n}" for p in plants for n in interfaces[p].names("input") if interfaces[p].ports[n].type == "Real"
        ]
        if len(outs) > len(ins):
            raise ModelInputError(
                f"component {comp.name}: {len(outs)} outputs ({', '.join(outs)}) but its plant "
                f"{', '.join(plants) or '(none)'} has {len(ins)} input(s) it could drive ({', '.join(ins) or 'none'})"
            )


def check_system(system: System, interfaces: dict[str, Interface]) -> list[Link]:
    """Every check of the module docstring, in that order; the scalar links if all pass."""
    links = expand(system, interfaces)
    check_sources(links)
    check_units(links, interfaces)
    check_parameters(system, interfaces, links)
    check_sample_periods(system, interfaces)
    check_feedthrough_loops(links, interfaces)
    check_controller_outputs(system, links, interfaces)
    return links
