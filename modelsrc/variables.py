"""FMI variable metadata of a model: the kinds the C layer distinguishes and one Float64 variable.

The kind decides a variable's causality and variability in the modelDescription
(fmu/model_description.py) and when the C layer lets an importer set it
(fmu/c/rbfmu_core.c, docs/fmi_layer.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum


class Kind(IntEnum):
    """Kinds of variables, numbered as the generated C sees them (RB_KIND_* in model_data.h)."""

    INDEPENDENT = 0
    STATE = 1
    INPUT = 2
    PARAM_FIXED = 3
    PARAM_TUNABLE = 4
    OUTPUT = 5
    DERIVATIVE = 6
    LOCAL = 7  # what the last doStep did (internal steps, rejections, step sizes): read-only


@dataclass
class Variable:
    """One FMI Float64 variable (scalar; arrays are flattened with 1-based names).

    start: start value in the variable's unit (None for calculated ones); unit: an FMI
    unit name of fmu/model_description.UNITS or None; derivative_of: for a state
    derivative, the value reference of its state; nominal: a state's nominal magnitude in
    its unit (modelsrc.nominals; the modelDescription's `nominal`), None for the others."""

    name: str
    kind: Kind
    start: float | None
    unit: str | None
    description: str
    derivative_of: int | None = None
    nominal: float | None = None


def vector_names(name: str, n: int) -> list[str]:
    """name[1], ..., name[n]: the flattened scalar names of an n-vector."""
    return [f"{name}[{i}]" for i in range(1, n + 1)]
