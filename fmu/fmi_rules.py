"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/gendocs/fmi_rules.py."""

from fmu.gendocs.fmi_rules import (
    C_DIR,
    any_states,
    call_rules,
    set_rules,
    state_bits,
    states,
)

__all__ = [
    "C_DIR",
    "any_states",
    "call_rules",
    "set_rules",
    "state_bits",
    "states",
]
