"""Input schedules of a scene: constants, tables held piecewise constant, and harmonic functions.

A scene's ``[inputs]`` give each input (a 3-vector: torque N·m, force N or pivot
acceleration m/s², in the frame its name says) as

* a constant ``[x, y, z]``;
* a table of rows ``[t, x, y, z]``, each row held from its time to the next (the
  driver puts a communication point on every switching time, so a row is held over
  whole communication steps);
* a harmonic function ``{ amplitude = [x, y, z], omega = w, phase = φ, offset = [x, y, z] }``:
  u(t) = offset + amplitude · cos(ω t + φ) (ω in rad/s, φ in rad; offset optional, default 0).

The physical input is `input_at` (a table's row in force at t, a harmonic's value at t).
A table switches only on communication points, so over a step it is constant; a harmonic
varies inside a step (`varies_in_step`): the project's driver gives it to the FMU at every
internal node through FMI 3.0 intermediate update, the references evaluate it in their
right-hand sides (continuous inputs, the default).

Held inputs (an option, as most importers do): the value a driver holds over [t0, t1] is
the input's MEAN over that interval (`input_mean`): for constants and tables it is the
row in force at t0; for a harmonic it is amplitude · (sin(ω t1 + φ) − sin(ω t0 + φ)) /
(ω (t1 − t0)), so that the integral of the held input over every step is exact. For a
pivot acceleration this makes the pivot velocity exact at every communication point
(docs/theory.md §7.3), not the position.

A user's value for one component (`--set 'a_pivot[3]=0'`, `hold_component`) replaces that
component's schedule by a constant for the whole run; the other components keep theirs.

Scalar inputs: a rotor's motor torque u_<name> (N·m, docs/theory.md §8) is one number, not
a 3-vector (`input_width`): a constant ``u``, table rows ``[t, u]``, a harmonic
``{ amplitude = a, omega = w, phase = φ }``; its FMU variable is ``u_<name>`` (no
component index), and its schedule is held as arrays of width 1.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

# Inputs named with this prefix are scalars (a rotor's motor torque u_<name>, N·m); every
# other input (tau_*, f_*, a_pivot) is a 3-vector. Force points are named f_<name>, so no
# vector input starts with it.
SCALAR_INPUT_PREFIXES = ("u_", "Omega_")  # Omega_<name>, Omega_dot_<name>: a speed-mode rotor's


def input_width(name: str) -> int:
    """Number of components of input `name`: 1 for a rotor's motor torque u_<name> or a
    speed-mode rotor's Omega_<name>, Omega_dot_<name>; else 3."""
    return 1 if name.startswith(SCALAR_INPUT_PREFIXES) else 3


def derivative_schedule(spec: InputSpec) -> InputSpec:
    """The schedule of d/dt of a constant (zeros) or a harmonic (A ω cos(ω t + φ + π/2)); a
    table has none (its steps are jumps): ValueError."""
    if isinstance(spec, Harmonic):
        return Harmonic(spec.amplitude * spec.omega, spec.omega, spec.phase + 0.5 * math.pi, np.zeros_like(spec.offset))
    if spec.ndim == 1:
        return np.zeros_like(spec)
    raise ValueError("a table has no derivative (it jumps)")


def component_names(base: str) -> list[str]:
    """The FMU variable names of input `base`: [base] for a scalar, base[1..3] for a vector."""
    return [base] if input_width(base) == 1 else [f"{base}[{k}]" for k in (1, 2, 3)]


@dataclass(frozen=True)
class Harmonic:
    """u(t) = offset + amplitude · cos(omega · t + phase): amplitude and offset (3,) (or (1,)
    for a scalar input) in the input's unit and frame, omega (rad/s, > 0), phase (rad). The
    offset is the scene file's (default 0) and holds the components a user set constant
    (`hold_component`)."""

    amplitude: np.ndarray
    omega: float
    phase: float = 0.0
    offset: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def at(self, t: float) -> np.ndarray:
        """Value at time t (s)."""
        return self.offset + self.amplitude * math.cos(self.omega * t + self.phase)

    def mean(self, t0: float, t1: float) -> np.ndarray:
        """Mean over [t0, t1] (s); the value at t0 when t1 == t0."""
        if t1 == t0:
            return self.at(t0)
        w, ph = self.omega, self.phase
        # sin a − sin b = 2 cos((a+b)/2) sin((a−b)/2): no cancellation for short steps
        half = 0.5 * w * (t1 - t0)
        return self.offset + self.amplitude * (math.cos(0.5 * w * (t0 + t1) + ph) * math.sin(half) / half)

    def derivative(self, t: float, order: int) -> np.ndarray:
        """d^order u / dt^order at t (s), order >= 1: A ω^n cos(ω t + φ + n π/2) (the
        offset drops out); for FMI 2.0 input derivatives."""
        return self.amplitude * (self.omega**order * math.cos(self.omega * t + self.phase + 0.5 * order * math.pi))

    def primitive(self, t: float, order: int) -> np.ndarray:
        """An order-fold antiderivative of u at t (s), order 1 or 2: offset t + A/ω sin(ωt + φ),
        offset t²/2 − A/ω² cos(ωt + φ) (for a pivot acceleration: a velocity, a position up
        to the constants of integration)."""
        w, arg = self.omega, self.omega * t + self.phase
        if order == 1:
            return self.offset * t + self.amplitude * (math.sin(arg) / w)
        if order == 2:
            return self.offset * (0.5 * t * t) - self.amplitude * (math.cos(arg) / (w * w))
        raise ValueError(f"order must be 1 or 2, got {order}")


InputSpec = np.ndarray | Harmonic  # (3,) constant, (n, 4) table, or a Harmonic


def input_mean(spec: InputSpec, t0: float, t1: float) -> np.ndarray:
    """The value a driver holds over the communication step [t0, t1] (s): the mean of the
    input there (a table's row in force at t0, since tables switch on communication points)."""
    if isinstance(spec, Harmonic):
        return spec.mean(t0, t1)
    if spec.ndim == 1:
        return spec
    k = int(np.searchsorted(spec[:, 0], t0, side="right")) - 1
    return spec[max(k, 0), 1:]


def input_at(spec: InputSpec, t: float) -> np.ndarray:
    """The physical input at time t (s): a constant, a table's row in force at t (rows hold
    from their time on), a harmonic's value at t."""
    if isinstance(spec, Harmonic):
        return spec.at(t)
    if spec.ndim == 1:
        return spec
    k = int(np.searchsorted(spec[:, 0], t, side="right")) - 1
    return spec[max(k, 0), 1:]


def varies_in_step(spec: InputSpec | None) -> bool:
    """True when the input changes inside a communication step (a harmonic with a non-zero
    amplitude); constants and tables (which switch on communication points) do not."""
    return isinstance(spec, Harmonic) and bool(np.any(spec.amplitude != 0.0))


def hold_component(spec: InputSpec | None, k: int, value: float, width: int = 3) -> InputSpec:
    """The schedule with component k (0, 1, 2) constant at `value` for the whole run, the
    other components unchanged: a constant's entry, a table's column, a harmonic's
    amplitude (set to 0, the value going to its offset). None (no schedule: zeros of
    `width` components) becomes a constant."""
    if isinstance(spec, Harmonic):
        amplitude, offset = spec.amplitude.copy(), spec.offset.copy()
        amplitude[k], offset[k] = 0.0, value
        return dataclasses.replace(spec, amplitude=amplitude, offset=offset)
    held = np.zeros(width) if spec is None else spec.copy()
    if held.ndim == 1:
        held[k] = value
    else:
        held[:, k + 1] = value
    return held


def input_component(name: str, input_names: Sequence[str]) -> tuple[str, int] | None:
    """(input, component 0..2) of a variable name such as 'a_pivot[3]' when it names a
    component of one of `input_names` (a scalar input 'u_wheel' is its own component 0),
    else None."""
    if name in input_names and input_width(name) == 1:
        return name, 0
    base, sep, index = name.partition("[")
    if not sep or base not in input_names or index not in ("1]", "2]", "3]"):
        return None
    return base, int(index[0]) - 1


def hold_inputs(
    inputs: Mapping[str, InputSpec], values: Mapping[str, float], input_names: Sequence[str]
) -> dict[str, InputSpec]:
    """The schedules with every input component named in `values` ('f_thr_a[1]' -> N)
    held constant at its value (`hold_component`); names that are not input components
    (start values, parameters) are ignored here."""
    held = dict(inputs)
    for name, value in values.items():
        comp = input_component(name, input_names)
        if comp is not None:
            held[comp[0]] = hold_component(held.get(comp[0]), comp[1], float(value), input_width(comp[0]))
    return held


def input_start(spec: InputSpec | None, width: int = 3) -> np.ndarray:
    """The input's value at t = 0 (its start value in the modelDescription); `width` zeros
    for None."""
    if spec is None:
        return np.zeros(width)
    if isinstance(spec, Harmonic):
        return spec.at(0.0)
    return spec[0, 1:] if spec.ndim == 2 else spec


def switch_times(spec: InputSpec) -> list[float]:
    """Times (s) at which a table switches rows (none for constants and harmonics)."""
    if isinstance(spec, np.ndarray) and spec.ndim == 2:
        return [float(t) for t in spec[:, 0]]
    return []


def zero_after(spec: InputSpec) -> float | None:
    """Time (s) after which the input stays zero (0.0 if it always is), None if never."""
    if isinstance(spec, Harmonic):
        return 0.0 if not (np.any(spec.amplitude != 0.0) or np.any(spec.offset != 0.0)) else None
    if spec.ndim == 1:
        return 0.0 if not np.any(spec != 0.0) else None
    nz = np.flatnonzero(np.any(spec[:, 1:] != 0.0, axis=1))
    if nz.size == 0:
        return 0.0
    if nz[-1] == spec.shape[0] - 1:
        return None
    return float(spec[nz[-1] + 1, 0])


def parse_input(
    fld: str,
    value: Any,
    vector: Callable[[str, Any, int], np.ndarray],
    number: Callable[..., float],
    fail: Callable[[str, str], Exception],
    width: int = 3,
) -> InputSpec:
    """One ``[inputs]`` entry of a scene file, validated with the scene reader's typed
    accessors (vector(field, value, n), number(field, value, positive=...), fail(field,
    message)) so that every error names the file and the field. width 1 (a scalar input,
    `input_width`): a number, rows [t, u], a harmonic with a number as amplitude."""
    scalar = width == 1

    def values(f: str, v: Any) -> np.ndarray:
        return np.array([number(f, v)]) if scalar else vector(f, v, 3)

    if isinstance(value, dict):
        unknown = set(value) - {"amplitude", "omega", "phase", "offset"}
        if unknown or "amplitude" not in value or "omega" not in value:
            amp = "a" if scalar else "[x, y, z]"
            raise fail(
                fld,
                f"a harmonic input is {{ amplitude = {amp}, omega = rad/s > 0, phase = rad (optional), "
                f"offset = {amp} (optional) }}, got keys {sorted(value)}",
            )
        return Harmonic(
            values(f"{fld}.amplitude", value["amplitude"]),
            number(f"{fld}.omega", value["omega"], positive=True),
            number(f"{fld}.phase", value.get("phase", 0.0)),
            values(f"{fld}.offset", value["offset"]) if "offset" in value else np.zeros(width),
        )
    if isinstance(value, list) and value and isinstance(value[0], list):
        table = np.array([vector(f"{fld}[{i + 1}]", r, width + 1) for i, r in enumerate(value)])
        if np.any(np.diff(table[:, 0]) <= 0):
            raise fail(fld, "table times (first column) must increase strictly")
        return table
    return values(fld, value)
