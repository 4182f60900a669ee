"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/exudyn/motion.py."""

from rbcheck.exudyn.motion import (
    MotionModel,
    moves,
    simulate,
    simulate_motion,
)

__all__ = [
    "MotionModel",
    "moves",
    "simulate",
    "simulate_motion",
]
