"""Reads the FMI state rules out of the C layer: which calls each state admits, when each variable kind is settable.

The rules live once, as tables in the hand-written C: the `MASK_<function>` lines at the
top of fmu/c/rbfmu_fmi3.c and rbfmu_fmi2.c, and `rb_set_mask[]` in rbfmu_core.c (the
style of the Modelica Reference FMUs' fmi3Functions.c). This module parses them so that
docs/fmi_layer.md's tables are generated from them (fmu/gendocs/generated_docs.py) and the fuzz
test's independent model is compared with them (tests/fmi/test_fmi_rules.py).
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

C_DIR = Path(__file__).resolve().parent.parent / "c"


@cache
def state_bits() -> dict[str, str]:
    """Mask bit name (M_INST, ...) -> state name as the FMU logs it (Instantiated, ...),
    from rbfmu_core.h (the bit order) and rbfmu_core.c (the names)."""
    header = (C_DIR / "rbfmu_core.h").read_text()
    order = re.search(r"typedef enum \{([^}]*)\} InstanceState;", header)
    bits = dict(re.findall(r"#define (M_[A-Z]+) \(1u << (ST_[A-Z_]+)\)", header))
    core = (C_DIR / "rbfmu_core.c").read_text()
    names = re.search(r"rb_state_names\[\] = \{([^}]*)\}", core)
    if not (order and names and bits):
        raise RuntimeError("cannot read the instance states from rbfmu_core.h/.c")
    st_order = [s.strip() for s in order.group(1).split(",") if s.strip()]
    st_names = re.findall(r'"([^"]+)"', names.group(1))
    st_name = dict(zip(st_order, st_names, strict=True))
    return {bit: st_name[st] for bit, st in bits.items()}


def states() -> tuple[str, ...]:
    """All instance state names in the order of the InstanceState enum."""
    return tuple(state_bits().values())


@cache
def any_states() -> frozenset[str]:
    """The states of M_ANY (rbfmu_core.h): every state but IntermediateUpdateMode, where only
    the calls that name M_IUM are allowed."""
    header = (C_DIR / "rbfmu_core.h").read_text()
    m = re.search(r"#define M_ANY \(([^)]*)\)", header)
    if not m:
        raise RuntimeError("cannot read M_ANY from rbfmu_core.h")
    bits = state_bits()
    return frozenset(bits[p.strip()] for p in m.group(1).split("|"))


def _mask_states(expr: str) -> frozenset[str]:
    """The state names of a mask expression such as `(M_INIT | M_STEP)`, `(M_ANY | M_IUM)`
    or `0`."""
    expr = expr.strip().strip("()").strip()
    if expr == "0":
        return frozenset()
    bits = state_bits()
    out: set[str] = set()
    for part in (p.strip() for p in expr.split("|")):
        if part == "M_ANY":
            out |= any_states()
        elif part in bits:
            out.add(bits[part])
        else:
            raise ValueError(f"unknown mask bit {part!r} in {expr!r}")
    return frozenset(out)


@cache
def call_rules(fmi_version: str = "3") -> dict[str, frozenset[str]]:
    """FMI function name -> the instance states in which it may be called, from the
    MASK_ table of rbfmu_fmi<version>.c, in the table's order."""
    text = (C_DIR / f"rbfmu_fmi{fmi_version}.c").read_text()
    rules = {fn: _mask_states(m) for fn, m in re.findall(r"^#define MASK_(fmi\w+)\s+(.+)$", text, re.M)}
    if not rules:
        raise RuntimeError(f"no MASK_ table in rbfmu_fmi{fmi_version}.c")
    return rules


@cache
def set_rules() -> dict[str, frozenset[str]]:
    """Variable kind (state, input, param_fixed, ...) -> the states in which an importer may
    set it, from rb_set_mask[] in rbfmu_core.c."""
    core = (C_DIR / "rbfmu_core.c").read_text()
    body = re.search(r"rb_set_mask\[\] = \{(.*?)\};", core, re.S)
    if not body:
        raise RuntimeError("no rb_set_mask[] table in rbfmu_core.c")
    pairs = re.findall(r"\[RB_KIND_([A-Z_]+)\]\s*=\s*([^,]+),", body.group(1))
    return {kind.lower(): _mask_states(m) for kind, m in pairs}
