"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/exudyn/rotors.py."""

from rbcheck.exudyn.rotors import (
    RotorInputFunction,
    covers,
    implicit_settings,
    simulate_gyrostat,
)

__all__ = [
    "RotorInputFunction",
    "covers",
    "implicit_settings",
    "simulate_gyrostat",
]
