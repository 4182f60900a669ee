"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/versions.py."""

from fmu.build.versions import (
    TOOL_TIMEOUT_S,
    VersionAction,
    version_lines,
)

__all__ = [
    "TOOL_TIMEOUT_S",
    "VersionAction",
    "version_lines",
]
