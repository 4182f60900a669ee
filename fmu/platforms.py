"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/platforms.py."""

from fmu.build.platforms import (
    PLATFORMS,
    Platform,
    binary_folder,
    host_platform,
    library_suffix,
    platforms_for,
    resolve_platforms,
)

__all__ = [
    "PLATFORMS",
    "Platform",
    "binary_folder",
    "host_platform",
    "library_suffix",
    "platforms_for",
    "resolve_platforms",
]
