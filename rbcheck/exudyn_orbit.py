"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/exudyn/orbit.py."""

from rbcheck.exudyn.orbit import (
    OVT,
    simulate_orbit,
)

__all__ = [
    "OVT",
    "simulate_orbit",
]
