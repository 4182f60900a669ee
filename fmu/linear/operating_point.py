"""The operating point of a linear model: the FMU's states, inputs and parameters, from start values or a run.

A point is what fmi3SetContinuousStates and fmi3SetFloat64 put a Model Exchange instance
at: every continuous state (the FMU's names and units), every input, and the parameters
set before initialisation (the rest keep their start values). It comes from the scene's
start values with `values` (`rbfmu linearize --set`: start states, parameters, inputs),
from a co-simulation run of the scene to a time t (`--at t`: the states reached at t and
the inputs the scene's schedules give at t), or from a trim (fmu.linear.trim).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType

import numpy as np

from modelsrc.errors import ModelInputError
from modelsrc.scene import Scene

from ..drive.logged_warnings import LoggedWarnings
from .model_exchange import ModelExchange


@dataclass(frozen=True)
class OperatingPoint:
    """states, inputs: name -> value at the point (every state and input of the FMU, its
    order); parameters: name -> value of the parameters (and `method`) set before
    initialisation; time: s (the run's time the point was taken at; 0 for start values);
    source: how it was made, for the reports. The point is immutable: the three mappings
    are read-only copies of those given (`with_values` makes a changed point), and x, u
    (the states and inputs as read-only vectors, FMU order) and the names of both
    (state_names, input_names) are made once, here, since every linearisation at the
    point reads them (fmu.linear.bench)."""

    states: Mapping[str, float]
    inputs: Mapping[str, float]
    parameters: Mapping[str, float] = field(default_factory=dict)
    time: float = 0.0
    source: str = "start values"
    x: np.ndarray = field(init=False, repr=False, compare=False)
    u: np.ndarray = field(init=False, repr=False, compare=False)
    state_names: tuple[str, ...] = field(init=False, repr=False, compare=False)
    input_names: tuple[str, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for kind, values in (("state", self.states), ("input", self.inputs), ("parameter", self.parameters)):
            for name, v in values.items():
                if not math.isfinite(float(v)):
                    raise ModelInputError(f"operating point: {kind} {name} must be finite, got {v}")
        if not math.isfinite(self.time):
            raise ModelInputError(f"operating point: time must be finite, got {self.time}")
        for name in ("states", "inputs", "parameters"):
            object.__setattr__(self, name, MappingProxyType(dict(getattr(self, name))))
        for name, values in (("x", self.states), ("u", self.inputs)):
            vector = np.fromiter(values.values(), float, len(values))
            vector.flags.writeable = False
            object.__setattr__(self, name, vector)
        object.__setattr__(self, "state_names", tuple(self.states))
        object.__setattr__(self, "input_names", tuple(self.inputs))

    def __reduce__(self) -> tuple:
        """Pickled and copied as the values it was made of (its read-only mappings are not
        picklable themselves): a LinearModel, which holds its point, goes to other processes."""
        return (OperatingPoint, (dict(self.states), dict(self.inputs), dict(self.parameters), self.time, self.source))

    def with_values(self, states: Mapping[str, float] | None = None, inputs: Mapping[str, float] | None = None,
                    source: str | None = None) -> OperatingPoint:  # fmt: skip
        """A copy with some states and inputs replaced (names must exist)."""
        for given, known, kind in ((states or {}, self.states, "state"), (inputs or {}, self.inputs, "input")):
            unknown = [n for n in given if n not in known]
            if unknown:
                raise ModelInputError(f"operating point: {unknown[0]!r} is not a {kind} of the FMU: {', '.join(known)}")
        return replace(
            self,
            states={**self.states, **{k: float(v) for k, v in (states or {}).items()}},
            inputs={**self.inputs, **{k: float(v) for k, v in (inputs or {}).items()}},
            source=source or self.source,
        )


def split_values(me: ModelExchange, values: Mapping[str, float]) -> dict[str, float]:
    """The entries of `values` that are parameters (or `method`): what only initialisation sets."""
    return {n: float(v) for n, v in values.items() if me.variables[n].causality == "parameter"}


def start_point(fmu: str | Path, values: Mapping[str, float] | None = None) -> OperatingPoint:
    """The point of the FMU's start values with `values` set (start states, parameters,
    inputs; ModelInputError for a name that cannot be set or a non-finite value), read after
    initialisation (which normalises a start quaternion). The warnings the FMU logs meanwhile
    are raised as FmuWarnings, as a run's (fmu.drive.logged_warnings). An input in `values`
    is set as given, its derived inputs (a rotor's Omega_dot_<name>) left at their start
    values: `held_start_values(scene, values)` gives what `rbfmu linearize --set` sets, the
    inputs held as a run holds them."""
    values = dict(values or {})
    with ModelExchange(fmu, values) as me, LoggedWarnings(me, first=0):
        x = me.states_now()
        u = me.get(me.value_references(me.inputs, me.inputs, "inputs"))
        params = split_values(me, values)
        return OperatingPoint(dict(zip(me.states, map(float, x))), dict(zip(me.inputs, map(float, u))), params)


def input_value(scene: Scene, name: str, time: float) -> float:
    """The scene's input component `name` ('tau_body[2]', 'Omega_p1') at `time` (s), from its schedule."""
    base, _, index = name.partition("[")
    return float(np.atleast_1d(scene.input_at(base, time))[int(index[:-1]) - 1 if index else 0])


def held_start_values(scene: Scene, values: Mapping[str, float], held: Iterable[str] = ()) -> dict[str, float]:
    """`values` (start values, parameters, inputs) with the inputs a run derives (a speed-mode
    rotor's Omega_dot_<name>, the time derivative of its Omega_<name> schedule, docs/theory.md
    §8.5) at t = 0 of the scene whose inputs in `values` and `held` (a trim's unknown inputs)
    are held constant, as `rbfmu run --set` holds them: 0 for a rotor whose speed is held, so
    that `--set Omega_p1=...` means the same point in `linearize` and `trim` as in a run;
    the schedule's own derivative for the others (the FMU's start value). A derived input
    given in `values` keeps the value given."""
    out = {n: float(v) for n, v in values.items()}
    fixed = {n: out.get(n, 0.0) for n in (*out, *held)}  # a held input's derivative does not depend on its value
    derived = sorted(n for n in scene.derived_input_names() if n not in out)
    if not derived:
        return out
    now = scene.with_inputs_held(fixed)
    return out | {n: input_value(now, n, 0.0) for n in derived}


def run_point(fmu: str | Path, scene: Scene, time: float, values: Mapping[str, float] | None = None,
              held: Iterable[str] = ()) -> OperatingPoint:  # fmt: skip
    """The point a co-simulation of the scene reaches at `time` (s, > 0): run_fmu with the
    scene's input schedules (and `values`: start values, parameters, inputs held constant),
    its states at `time`, and the inputs the schedules give at `time`, those in `held` (a
    trim's unknown inputs) held from `time` on at their value there (so a held rotor speed's
    derivative Omega_dot_<name> is 0, as in `held_start_values`)."""
    from ..drive.run import run_fmu

    if not (math.isfinite(time) and time > 0):
        raise ModelInputError(f"--at: the time must be a finite number > 0 (s), got {time}")
    values = dict(values or {})
    start = start_point(fmu, values)  # checks the names and values before the run
    res = run_fmu(fmu, scene, stop_time=time, start_values=values, outputs=list(start.states))
    fixed = {k: v for k, v in values.items() if k in start.inputs}
    fixed |= {k: input_value(scene, k, time) for k in held if k in start.inputs and k not in fixed}
    now = scene.with_inputs_held(fixed)
    inputs = dict(start.inputs)
    for name in inputs:
        if name.partition("[")[0] in now.inputs:
            inputs[name] = input_value(now, name, time)
    states = {n: float(res.values[n][-1]) for n in start.states}
    return OperatingPoint(states, inputs, start.parameters, float(res.time[-1]), f"run to t = {res.time[-1]:g} s")
