"""Alias until 0.5.0 (CHANGELOG.md): the code lives in fmu/build/cross_compile.py."""

from fmu.build.cross_compile import (
    CACHE_ENV,
    binary_name,
    build_cross,
    cache_root,
    compile_object,
    link,
    object_key,
    run_zig,
    target_flags,
    zig_version,
)

__all__ = [
    "CACHE_ENV",
    "binary_name",
    "build_cross",
    "cache_root",
    "compile_object",
    "link",
    "object_key",
    "run_zig",
    "target_flags",
    "zig_version",
]
