"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/closed_forms/free_asymmetric.py."""

from rbcheck.closed_forms.free_asymmetric import (
    ellippi_complete,
    ellippi_jacobi,
    ellippi_reduced,
    jacobi_reduced,
    omega,
    solve,
)

__all__ = [
    "ellippi_complete",
    "ellippi_jacobi",
    "ellippi_reduced",
    "jacobi_reduced",
    "omega",
    "solve",
]
