"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/build_fmu.py."""

from fmu.build.build_fmu import (
    CFLAGS,
    CORE_SOURCES,
    GENERATED_EXTRA,
    BuildError,
    ModelInputError,
    build_all,
    build_fmu,
    build_key,
    c_sources,
    ensure_fmu,
    platform_tuple,
)

__all__ = [
    "CFLAGS",
    "CORE_SOURCES",
    "GENERATED_EXTRA",
    "BuildError",
    "ModelInputError",
    "build_all",
    "build_fmu",
    "build_key",
    "c_sources",
    "ensure_fmu",
    "platform_tuple",
]
