"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/kepler.py."""

from rbcheck.closed_forms.kepler import (
    Elements,
    elements,
    propagate,
    quadrupole_bound,
)

__all__ = [
    "Elements",
    "elements",
    "propagate",
    "quadrupole_bound",
]
