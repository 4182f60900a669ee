"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/free_symmetric.py."""

from rbcheck.closed_forms.free_symmetric import (
    body_precession_about_L,
    precession_rate,
    solve,
)

__all__ = [
    "body_precession_about_L",
    "precession_rate",
    "solve",
]
