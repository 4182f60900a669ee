"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/archive_docs.py."""

from fmu.build.archive_docs import (
    SOURCE_BUILD,
    SOURCES,
    frame_of,
    index_html,
    oldest_system,
)

__all__ = [
    "SOURCES",
    "SOURCE_BUILD",
    "frame_of",
    "index_html",
    "oldest_system",
]
