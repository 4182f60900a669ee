"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/baselines/motion.py."""

from rbcheck.baselines.motion import (
    MotionODE,
    central_field,
    central_potential,
    integrate,
    moves,
)

__all__ = [
    "MotionODE",
    "central_field",
    "central_potential",
    "integrate",
    "moves",
]
