"""The values a run sets by name (run_fmu's and simulate's start_values, `rbfmu run --set`): checked once, one rule.

A value is a number (a float, an int or its text, finite) or, for `method`, a method's
name or its enumeration value (modelsrc.methods), as the command line takes it; anything
else is refused with a ModelInputError naming the value and what is allowed, never a raw
Python exception. Values almost surely given in the wrong unit (an orbit rate n_orbit
faster than any orbit, a start orbit_angle beyond a full turn) are warned about
(modelsrc.unit_mistakes), not refused.
"""

from __future__ import annotations

from collections.abc import Mapping

from modelsrc import unit_mistakes
from modelsrc.errors import ModelInputError, finite_number
from modelsrc.methods import METHODS, enumeration_value, method_by_value

# Every method's name -> its enumeration value (an FMU compiles in some of them).
ALL_METHODS = {m.name: m.value for m in METHODS.values()}


def method_value(value: object, where: str, methods: Mapping[str, int] | None = None) -> float:
    """The enumeration value of a method given by name ('gauss4') or value (3), among
    `methods` (name -> value: those compiled into one FMU; default every method), else a
    ModelInputError naming the value and the allowed ones."""
    allowed = dict(ALL_METHODS if methods is None else methods)
    v = enumeration_value(value, allowed) if not isinstance(value, bool) else None
    if v is None:
        names = ", ".join(f"{val} = {name}" for name, val in allowed.items())
        known = None if isinstance(value, bool) else enumeration_value(value, ALL_METHODS)
        if known is not None:  # a method, but not one of these (not compiled into this FMU)
            name = method_by_value(int(known)).name
            raise ModelInputError(f"{where}: method {name} ({int(known)}) is not compiled into this FMU (those of "
                                  f"the scene's [experiment] methods that apply to it); allowed: {names}")  # fmt: skip
        raise ModelInputError(f"{where}: method {value!r} is not a method name or its value; allowed: {names}")
    return v


def check_start_values(
    values: Mapping[str, object] | None,
    where: str = "start_values",
    methods: Mapping[str, int] | None = None,
    warn: bool = True,
) -> dict[str, float]:
    """{name: value as float}: each value a finite number (ModelInputError naming `where`,
    the name and the value otherwise), `method` by name or value among `methods` (default
    every method). warn: warn (ModelInputWarning) for values that are almost surely unit
    mistakes; the names themselves are checked against the FMU when the values are set."""
    if values is None:
        return {}
    if not isinstance(values, Mapping):
        raise ModelInputError(f"{where} must be a mapping of variable name to value, got {type(values).__name__}")
    out: dict[str, float] = {}
    for name, value in values.items():
        if not isinstance(name, str):
            raise ModelInputError(f"{where}: variable names are strings, got {name!r}")
        at = f"{where}[{name!r}]"
        if name == "method":
            out[name] = method_value(value, at, methods)
            continue
        if isinstance(value, bool):  # float(True) is 1.0: a flag is no physical value
            raise ModelInputError(f"{at}: value {value!r} is not a number")
        out[name] = finite_number(value, at)
        if warn:
            unit_mistakes.start_value(name, name, out[name])
    return out
