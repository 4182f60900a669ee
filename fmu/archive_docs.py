"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/archive_docs.py."""

from fmu.build.archive_docs import (
    EQUATIONS,
    ROTOR_EQUATIONS,
    SOURCE_BUILD,
    SOURCES,
    frame_of,
    index_html,
    oldest_system,
)

__all__ = [
    "EQUATIONS",
    "ROTOR_EQUATIONS",
    "SOURCES",
    "SOURCE_BUILD",
    "frame_of",
    "index_html",
    "oldest_system",
]
