"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/slew.py."""

from rbcheck.closed_forms.slew import (
    SLEW_GAINS,
    PDSlew,
    eigenaxis_reference,
    open_loop_torques,
    slew_law,
)

__all__ = [
    "SLEW_GAINS",
    "PDSlew",
    "eigenaxis_reference",
    "open_loop_torques",
    "slew_law",
]
