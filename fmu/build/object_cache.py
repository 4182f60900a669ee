"""A content-keyed cache of compiled object files, shared by the host build (gcc) and the cross builds (zig cc).

An object file is a function of the unit's text, the text of every local header it includes
(transitively, from the FMU's sources/), the flags and the compiler. Its key hashes exactly
those, so a rebuild of the same content (the same scene again, the same model in FMI 2.0 and
3.0, a controller's hand-written layer for another controller of the same size) only links;
a change of one generated file recompiles only the units that include it. The compiler's
diagnostics are kept beside the object, so a cached build reports the same warnings as the
build that made it.

Cache directory: $RBFMU_CACHE_DIR, else the user's cache dir (platformdirs:
~/.cache/rbfmu on Linux, ~/Library/Caches/rbfmu on macOS, %LOCALAPPDATA%\\rbfmu\\Cache
on Windows); never the checkout.
"""

from __future__ import annotations

import hashlib
import os
import re
from collections.abc import Callable
from pathlib import Path

import platformdirs

CACHE_ENV = "RBFMU_CACHE_DIR"
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def cache_root() -> Path:
    """Where compiled objects (and zig's own cache) are kept ($RBFMU_CACHE_DIR or the
    user's cache directory)."""
    return Path(os.environ.get(CACHE_ENV) or platformdirs.user_cache_dir("rbfmu"))


def local_headers(src_dir: Path, name: str, seen: set[str] | None = None) -> set[str]:
    """The local headers `name` includes, transitively (#include "..." found in src_dir)."""
    seen = set() if seen is None else seen
    for inc in _INCLUDE.findall((src_dir / name).read_text(errors="replace")):
        if inc not in seen and (src_dir / inc).is_file():
            seen.add(inc)
            local_headers(src_dir, inc, seen)
    return seen


def content_key(src_dir: Path, unit: str, compiler: str, flags: list[str]) -> str:
    """Key of one object: the compiler (its name and version), the flags, the unit and
    every local header it includes."""
    digest = hashlib.sha256(repr((compiler, flags, unit)).encode())
    for name in [unit, *sorted(local_headers(src_dir, unit))]:
        digest.update(name.encode() + b"\0" + (src_dir / name).read_bytes() + b"\0")
    return digest.hexdigest()


def cached_object(key: str, compile_to: Callable[[Path], str]) -> tuple[Path, str, bool]:
    """(object file in the cache, the compiler's diagnostics, True when it was cached).

    compile_to(path) compiles the unit into `path` and returns the compiler's diagnostics;
    it raises when the compiler fails, and then nothing is cached."""
    obj = cache_root() / "objects" / key[:2] / f"{key}.o"
    log = obj.with_suffix(".log")
    if obj.is_file() and log.is_file():
        return obj, log.read_text(), True
    obj.parent.mkdir(parents=True, exist_ok=True)
    # unique names, renamed into place: concurrent builds never see half-written entries
    tmp_obj = obj.with_name(f"{key}.{os.getpid()}.{id(compile_to)}.tmp.o")
    try:
        diagnostics = compile_to(tmp_obj)
    except BaseException:
        tmp_obj.unlink(missing_ok=True)
        raise
    tmp_log = log.with_suffix(f".{os.getpid()}.{id(compile_to)}.tmp")
    tmp_log.write_text(diagnostics)
    os.replace(tmp_log, log)
    os.replace(tmp_obj, obj)
    return obj, diagnostics, False
