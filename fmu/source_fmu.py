"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/source_fmu.py."""

from fmu.build.source_fmu import (
    cmake_lists,
)

__all__ = [
    "cmake_lists",
]
