"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/model_description.py."""

from fmu.build.model_description import (
    BUILD_NOTE,
    CAPABILITIES,
    CAUSALITY,
    SOURCE_COMPILER_OPTIONS,
    UNITS,
    VERSION,
    build_description_xml,
    check_attribute_values,
    fmi2_model_description,
    fmi3_model_description,
)

__all__ = [
    "BUILD_NOTE",
    "CAPABILITIES",
    "CAUSALITY",
    "SOURCE_COMPILER_OPTIONS",
    "UNITS",
    "VERSION",
    "build_description_xml",
    "check_attribute_values",
    "fmi2_model_description",
    "fmi3_model_description",
]
