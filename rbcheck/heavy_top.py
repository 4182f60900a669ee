"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/heavy_top.py."""

from rbcheck.closed_forms.heavy_top import (
    HeavyTop,
    TopConstants,
    TopInit,
    TopParams,
    constants,
    fast_top_nutation_amplitude,
    fast_top_nutation_frequency,
    fast_top_precession_rate,
    init_from_state,
    nutation_period,
    omega,
    quaternion,
    roots,
    sleeping_threshold,
    solve,
)

__all__ = [
    "HeavyTop",
    "TopConstants",
    "TopInit",
    "TopParams",
    "constants",
    "fast_top_nutation_amplitude",
    "fast_top_nutation_frequency",
    "fast_top_precession_rate",
    "init_from_state",
    "nutation_period",
    "omega",
    "quaternion",
    "roots",
    "sleeping_threshold",
    "solve",
]
