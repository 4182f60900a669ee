"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/frame_kinematics.py."""

from rbcheck.closed_forms.frame_kinematics import (
    arm_wrist,
)

__all__ = [
    "arm_wrist",
]
