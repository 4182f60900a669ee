"""A sampled-data controller: its FMI variables and the CasADi functions the C layer (fmu/c/rbctl_*.c) calls.

The law is written once in CasADi (one module per law in this folder) and code-generated like
a scene's model (fmu/build/controller_build.py). Three functions, called by name:

- ``ctrl_output(u, p, z) -> y``: the outputs at a sample point, from the inputs u at that point
  (direct feedthrough), the parameters p and the discrete states z;
- ``ctrl_update(u, p, z) -> z_next``: the discrete states after a sample point;
- ``ctrl_checks(p) -> ok``: 1 where a parameter condition holds, 0 where it is violated (the C
  layer refuses ExitInitializationMode, or a tunable parameter set in Step Mode, naming the
  condition's text, ``check_texts``).

The value references are the indices of one double buffer:
``[time | inputs u | parameters p | outputs y | discrete states z]`` (docs/theory.md §12).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

import casadi as ca


class CKind(StrEnum):
    """Kinds of a controller's variables, in value-reference order (RC_KIND_* in controller_data.h)."""

    INDEPENDENT = "independent"
    INPUT = "input"
    PARAM_TUNABLE = "tunable"
    PARAM_FIXED = "fixed"
    OUTPUT = "output"
    STATE = "discrete_state"


C_KIND_CODES = {CKind.INDEPENDENT: 0, CKind.INPUT: 1, CKind.PARAM_TUNABLE: 2, CKind.PARAM_FIXED: 3,
                CKind.OUTPUT: 4, CKind.STATE: 5}  # fmt: skip


@dataclass(frozen=True)
class CVar:
    """One Float64 variable of a controller FMU: name (the plant's, so a system connects name to
    name), kind, start value in its unit (None for time and outputs), FMI unit name, description."""

    name: str
    kind: CKind
    start: float | None
    unit: str | None
    description: str


@dataclass
class ControllerModel:
    """A controller ready to build: name, description, the plant it was made for, its sample
    period Ts (s), its variables (value-reference order), the generated functions and the
    texts of ctrl_checks' conditions. `feedthrough`: output name -> the input names it
    depends on directly (modelDescription's dependencies)."""

    name: str
    description: str
    plant: str
    sample_period: float
    variables: list[CVar]
    functions: dict[str, ca.Function]
    check_texts: list[str]
    feedthrough: dict[str, list[str]] = field(default_factory=dict)

    def names(self, kind: CKind) -> list[str]:
        """The names of the variables of one kind, in value-reference order."""
        return [v.name for v in self.variables if v.kind == kind]

    def value_reference(self, name: str) -> int:
        """The value reference (buffer index) of a variable."""
        return [v.name for v in self.variables].index(name)


def ordered_variables(
    inputs: list[CVar], tunable: list[CVar], fixed: list[CVar], outputs: list[CVar], states: list[CVar]
) -> list[CVar]:
    """time, then each kind in the buffer's order (the C layer relies on it)."""
    time = CVar("time", CKind.INDEPENDENT, None, "s", "simulation time")
    return [time, *inputs, *tunable, *fixed, *outputs, *states]
