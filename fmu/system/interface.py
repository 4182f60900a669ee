"""A component's interface as the system checks need it: its variables' causality and unit, and its feedthrough.

Read from the component's built FMU (modelDescription.xml through fmpy). Feedthrough — which
inputs an output depends on at the same communication point — is read from the
ModelStructure's `dependencies`; where an output declares none, FMI says it depends on every
input. rbfmu's scene FMUs declare no dependencies yet, so for them it is computed from the
same CasADi function whose C gives the outputs (`model_outputs(x, u, p, d)`, the structural
sparsity of ∂y/∂u): states, reported as outputs, never depend on the inputs at the same
instant (docs/theory.md: the inputs act through the step).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from fmpy import read_model_description

from modelsrc.model import build_model
from modelsrc.scene import Scene
from modelsrc.variables import Kind


@dataclass(frozen=True)
class Port:
    """One variable: causality ('input', 'output', 'parameter', ...), unit ('' if none),
    type ('Real', 'Enumeration', ...), the FMI value reference, the start value (None: none)."""

    name: str
    causality: str
    unit: str
    type: str
    value_reference: int
    start: float | None = None


@dataclass(frozen=True)
class Interface:
    """A component's variables by name, the FMI version of its FMU, and for each output the
    inputs it depends on at the same communication point (feedthrough)."""

    ports: dict[str, Port]
    fmi_version: str
    feedthrough: dict[str, frozenset[str]]
    default_step: float | None = None

    def names(self, causality: str) -> list[str]:
        """The variables of one causality, in value-reference order."""
        return [p.name for p in self.ports.values() if p.causality == causality]


def read_interface(fmu: str | Path) -> Interface:
    """The interface of an FMU file from its modelDescription.xml."""
    md = read_model_description(str(fmu))
    ports = {}
    for v in md.modelVariables:
        unit = v.unit or (v.declaredType.unit if v.declaredType is not None and v.declaredType.unit else "") or ""
        try:
            start = float(v.start) if v.start is not None else None
        except (TypeError, ValueError):
            start = None
        ports[v.name] = Port(v.name, v.causality, unit, v.type, v.valueReference, start)
    inputs = frozenset(p.name for p in ports.values() if p.causality == "input")
    feed: dict[str, frozenset[str]] = {}
    for u in md.outputs:
        deps = u.dependencies
        feed[u.variable.name] = inputs if deps is None else frozenset(d.name for d in deps) & inputs
    step = md.defaultExperiment.stepSize if md.defaultExperiment is not None else None
    return Interface(ports, md.fmiVersion, feed, float(step) if step else None)


def scene_feedthrough(scene: Scene) -> dict[str, frozenset[str]]:
    """For a scene's FMU: each output -> the inputs it depends on at the same instant, from the
    sparsity of ∂y/∂u of the CasADi output function (states: none)."""
    model = build_model(scene)
    inputs = [v.name for v in model.variables if v.kind == Kind.INPUT]
    derived = [v.name for v in model.variables if v.kind == Kind.OUTPUT]
    feed = {v.name: frozenset[str]() for v in model.variables if v.kind == Kind.STATE}
    if inputs and derived:
        sp = model.functions["model_outputs"].sparsity_jac("u", "y")
        rows, cols = sp.get_triplet()
        deps: dict[int, set[str]] = {}
        for r, c in zip(rows, cols):
            deps.setdefault(r, set()).add(inputs[c])
        feed.update({n: frozenset(deps.get(k, ())) for k, n in enumerate(derived)})
    else:
        feed.update({n: frozenset[str]() for n in derived})
    return feed
