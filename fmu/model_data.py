"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/model_data.py."""

from fmu.build.model_data import (
    MAX_INPUT_ORDER,
    MAX_OUTPUT_ORDER,
    write_model_data,
)

__all__ = [
    "MAX_INPUT_ORDER",
    "MAX_OUTPUT_ORDER",
    "write_model_data",
]
