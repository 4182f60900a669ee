"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/gravity_gradient.py, baselines/orbit.py."""

from rbcheck.baselines.orbit import (
    reference,
)
from rbcheck.closed_forms.gravity_gradient import (
    jacobi_integral,
    lvlh_start,
    pitch_frequency,
    pitch_period,
    roll_yaw_frequencies,
)

__all__ = [
    "jacobi_integral",
    "lvlh_start",
    "pitch_frequency",
    "pitch_period",
    "reference",
    "roll_yaw_frequencies",
]
