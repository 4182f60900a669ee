"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/baselines/gyrostat.py."""

from rbcheck.baselines.gyrostat import (
    GyrostatODE,
    covers,
    integrate_gyrostat,
)

__all__ = [
    "GyrostatODE",
    "covers",
    "integrate_gyrostat",
]
