"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/free_flight.py."""

from rbcheck.closed_forms.free_flight import (
    accelerating_pivot_top,
    harmonic_motion,
    held_pivot_motion,
    impulse,
    parabola,
    shaker_position_bound,
    turn_to_down,
)

__all__ = [
    "accelerating_pivot_top",
    "harmonic_motion",
    "held_pivot_motion",
    "impulse",
    "parabola",
    "shaker_position_bound",
    "turn_to_down",
]
