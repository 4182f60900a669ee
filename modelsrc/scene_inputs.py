"""Input schedules of a scene: constants, tables held piecewise constant, and harmonic functions.

A scene's ``[inputs]`` give each input (a 3-vector: torque N·m, force N or pivot
acceleration m/s², in the frame its name says) as

* a constant ``[x, y, z]``;
* a table of rows ``[t, x, y, z]``, each row held from its time to the next (the
  driver puts a communication point on every switching time, so a row is held over
  whole communication steps);
* a harmonic function ``{ amplitude = [x, y, z], omega = w, phase = φ }``:
  u(t) = amplitude · cos(ω t + φ) (ω in rad/s, φ in rad).

Co-simulation holds an input constant over each communication step (zero-order hold).
The value a driver holds over [t0, t1] is the input's MEAN over that interval
(`input_mean`): for constants and tables it is the row in force at t0; for a harmonic
it is amplitude · (sin(ω t1 + φ) − sin(ω t0 + φ)) / (ω (t1 − t0)), so that the integral
of the held input over every step is exact. For a pivot acceleration this makes the
pivot velocity exact at every communication point (docs/theory.md §7.3).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Harmonic:
    """u(t) = amplitude · cos(omega · t + phase): amplitude (3,) in the input's unit and
    frame, omega (rad/s, > 0), phase (rad)."""

    amplitude: np.ndarray
    omega: float
    phase: float = 0.0

    def at(self, t: float) -> np.ndarray:
        """Value at time t (s)."""
        return self.amplitude * math.cos(self.omega * t + self.phase)

    def mean(self, t0: float, t1: float) -> np.ndarray:
        """Mean over [t0, t1] (s); the value at t0 when t1 == t0."""
        if t1 == t0:
            return self.at(t0)
        w, ph = self.omega, self.phase
        # sin a − sin b = 2 cos((a+b)/2) sin((a−b)/2): no cancellation for short steps
        half = 0.5 * w * (t1 - t0)
        return self.amplitude * (math.cos(0.5 * w * (t0 + t1) + ph) * math.sin(half) / half)


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


def input_start(spec: InputSpec | None) -> np.ndarray:
    """The input's value at t = 0 (its start value in the modelDescription); zeros for None."""
    if spec is None:
        return np.zeros(3)
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
        return 0.0 if not np.any(spec.amplitude != 0.0) else None
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
) -> InputSpec:
    """One ``[inputs]`` entry of a scene file, validated with the scene reader's typed
    accessors (vector(field, value, n), number(field, value, positive=...), fail(field,
    message)) so that every error names the file and the field."""
    if isinstance(value, dict):
        unknown = set(value) - {"amplitude", "omega", "phase"}
        if unknown or "amplitude" not in value or "omega" not in value:
            raise fail(
                fld,
                "a harmonic input is { amplitude = [x, y, z], omega = rad/s > 0, phase = rad (optional) }, "
                f"got keys {sorted(value)}",
            )
        return Harmonic(
            vector(f"{fld}.amplitude", value["amplitude"], 3),
            number(f"{fld}.omega", value["omega"], positive=True),
            number(f"{fld}.phase", value.get("phase", 0.0)),
        )
    if isinstance(value, list) and value and isinstance(value[0], list):
        table = np.array([vector(f"{fld}[{i + 1}]", r, 4) for i, r in enumerate(value)])
        if np.any(np.diff(table[:, 0]) <= 0):
            raise fail(fld, "table times (first column) must increase strictly")
        return table
    return vector(fld, value, 3)
