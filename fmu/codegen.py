"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/codegen.py."""

from fmu.build.codegen import (
    BUILD_HEADER_LINE,
    CS_FUNCTIONS,
    generate_c,
    prepend_build_header,
    step_function_names,
)

__all__ = [
    "BUILD_HEADER_LINE",
    "CS_FUNCTIONS",
    "generate_c",
    "prepend_build_header",
    "step_function_names",
]
