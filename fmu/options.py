"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/drive/options.py."""

from fmu.drive.options import (
    parse_set,
    split_assignment,
)

__all__ = [
    "parse_set",
    "split_assignment",
]
