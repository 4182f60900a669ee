"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/skewed_bar.py and exudyn/skewed_bar.py."""

from rbcheck.closed_forms.skewed_bar import (
    bearing_torque,
)
from rbcheck.exudyn.skewed_bar import (
    OVT,
    exudyn_revolute,
)

__all__ = [
    "OVT",
    "bearing_torque",
    "exudyn_revolute",
]
