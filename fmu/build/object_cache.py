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

Size: the objects are kept within $RBFMU_CACHE_MAX_MB megabytes (default 512; a whole test
suite stores about 30 MB). When a new object takes them over it, the least recently used
objects go (a hit counts as a use) until they fill 80 % of it, so that the next builds do
not prune again at once. The size is checked at a process's first store and every 16th
after it. The objects a process has taken or stored are never pruned by it
(its build links them after its last compile); for another process they are the most
recent, so they go last.
"""

from __future__ import annotations

import hashlib
import math
import os
import re
from collections.abc import Callable
from pathlib import Path

import platformdirs

from .build_error import BuildError

CACHE_ENV = "RBFMU_CACHE_DIR"
LIMIT_ENV = "RBFMU_CACHE_MAX_MB"
DEFAULT_LIMIT_MB = 512.0
PRUNE_TO = 0.8  # of the limit: room for the next builds before the next pruning
# objects this process has handed out: a build links them after the last compile, so the
# pruning after a later compile of the same build must not take them
_handed_out: set[Path] = set()
# the cache is scanned for its size at a process's first store and every RESCAN_EVERY-th
# after it (a scan stats every object: 11-12 ms for the 897 of a test run, measured), so the limit can
# be passed by at most RESCAN_EVERY objects per process (a few MB) between scans
RESCAN_EVERY = 16
_stores = [0]
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def cache_root() -> Path:
    """Where compiled objects (and zig's own cache) are kept ($RBFMU_CACHE_DIR or the
    user's cache directory)."""
    return Path(os.environ.get(CACHE_ENV) or platformdirs.user_cache_dir("rbfmu"))


def limit_bytes() -> int:
    """The objects' size limit in bytes ($RBFMU_CACHE_MAX_MB, default 512 MB); BuildError
    naming the value when it is not a number > 0."""
    raw = os.environ.get(LIMIT_ENV, "").strip()
    if not raw:
        return int(DEFAULT_LIMIT_MB * 2**20)
    try:
        mb = float(raw)
    except ValueError:
        mb = math.nan
    if not (math.isfinite(mb) and mb > 0):
        raise BuildError(
            f"${LIMIT_ENV}={raw!r}: the object cache's size limit must be a number of megabytes > 0 "
            f"(default {DEFAULT_LIMIT_MB:g}); unset it for the default"
        )
    return int(mb * 2**20)


def prune(limit: int) -> int:
    """Remove the least recently used objects (and their diagnostics) while the objects
    take more than `limit` bytes, down to PRUNE_TO of it; return how many were removed.
    Another build removing the same files at the same time is harmless."""
    entries = []
    for obj in (cache_root() / "objects").glob("*/*.o"):
        if obj.name.count(".") != 1:  # KEY.PID.ID.tmp.o: being written by a build now
            continue
        try:
            st = obj.stat()
        except FileNotFoundError:  # removed meanwhile by another build
            continue
        entries.append((st.st_mtime_ns, st.st_size, obj))
    total = sum(size for _, size, _ in entries)
    if total <= limit:
        return 0
    removed = 0
    for _, size, obj in sorted(entries, key=lambda e: e[0]):
        if total <= PRUNE_TO * limit:
            break
        if obj in _handed_out:
            continue
        obj.unlink(missing_ok=True)
        obj.with_suffix(".log").unlink(missing_ok=True)
        total -= size
        removed += 1
    return removed


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
    limit = limit_bytes()  # a bad setting is refused before anything is compiled
    obj = cache_root() / "objects" / key[:2] / f"{key}.o"
    log = obj.with_suffix(".log")
    if obj.is_file() and log.is_file():
        try:
            os.utime(obj)  # used now: the last to go when the cache is pruned
            diagnostics = log.read_text()
            _handed_out.add(obj)
            return obj, diagnostics, True
        except FileNotFoundError:  # pruned by another build just now: compile it again
            pass
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
    _handed_out.add(obj)
    _stores[0] += 1
    if _stores[0] % RESCAN_EVERY == 1:  # the first store of a process, then every RESCAN_EVERY-th
        prune(limit)
    return obj, diagnostics, False
