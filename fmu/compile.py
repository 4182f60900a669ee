"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/compile.py."""

from fmu.build.compile import (
    ADAPTERS,
    C_DIR,
    CFLAGS,
    CORE,
    CORE_SOURCES,
    GENERATED_EXTRA,
    GENERATED_SOURCE,
    HANDWRITTEN_EXTRA,
    BuildError,
    c_sources,
    compile_native,
    units,
)

__all__ = [
    "ADAPTERS",
    "CFLAGS",
    "CORE",
    "CORE_SOURCES",
    "C_DIR",
    "GENERATED_EXTRA",
    "GENERATED_SOURCE",
    "HANDWRITTEN_EXTRA",
    "BuildError",
    "c_sources",
    "compile_native",
    "units",
]
