"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/build_check.py."""

from fmu.build.build_check import (
    COMMUNICATION_POINTS,
    BuildCheck,
    check_build,
    reference_method,
)

__all__ = [
    "COMMUNICATION_POINTS",
    "BuildCheck",
    "check_build",
    "reference_method",
]
