"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/terminal/progress.py."""

from fmu.terminal.progress import (
    progress_bar,
)

__all__ = [
    "progress_bar",
]
