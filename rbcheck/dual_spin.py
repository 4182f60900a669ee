"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/dual_spin.py."""

from rbcheck.closed_forms.dual_spin import (
    growth_rate,
    nutation_frequency,
    stability_factors,
    stable,
    transverse_axes,
    transverse_ratio,
)

__all__ = [
    "growth_rate",
    "nutation_frequency",
    "stability_factors",
    "stable",
    "transverse_axes",
    "transverse_ratio",
]
