"""Cross-compilation of an FMU binary with `zig cc` for other platforms, with a content-keyed object cache.

`zig cc -target T` (the `ziglang` package, pinned in constraints.txt) is clang with the C
library headers and import stubs of every target, so the FMU's C builds for Windows,
macOS and ARM Linux on this machine with no system packages. Each object file is cached
under a key of what it is a function of: the unit's text and that of every header it
includes (transitively, from sources/), the target, the flags and zig's version. A
rebuild of the same scene therefore only links; a change of one generated file
recompiles only the units that include it. zig's own cache (its C runtimes, e.g.
MinGW's for Windows, built once in minutes) lives under the same directory.

Cache directory: $RBFMU_CACHE_DIR, else the user's cache dir (platformdirs:
~/.cache/rbfmu on Linux, ~/Library/Caches/rbfmu on macOS, %LOCALAPPDATA%\\rbfmu\\Cache
on Windows); never the checkout.
"""

from __future__ import annotations

import functools
import hashlib
import os
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import platformdirs

from .compile import CFLAGS, BuildError, units
from .platforms import PLATFORMS, library_suffix

CACHE_ENV = "RBFMU_CACHE_DIR"
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def cache_root() -> Path:
    """Where cross-compiled objects and zig's own cache are kept ($RBFMU_CACHE_DIR or the
    user's cache directory)."""
    return Path(os.environ.get(CACHE_ENV) or platformdirs.user_cache_dir("rbfmu"))


def _zig_env() -> dict[str, str]:
    zig_cache = str(cache_root() / "zig")
    return {**os.environ, "ZIG_GLOBAL_CACHE_DIR": zig_cache, "ZIG_LOCAL_CACHE_DIR": zig_cache}


def run_zig(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """Run `zig ARGS` of the ziglang package with the cache directories of cache_root()."""
    return subprocess.run(
        [sys.executable, "-m", "ziglang", *args], capture_output=True, text=True, env=_zig_env(), cwd=cwd
    )


@functools.cache
def zig_version() -> str:
    """The version of the zig compiler of the `ziglang` package; BuildError if it is missing."""
    try:
        proc = run_zig("version")
    except OSError as exc:  # pragma: no cover - the interpreter itself is missing
        raise BuildError(f"cannot run zig: {exc}") from exc
    if proc.returncode != 0:
        raise BuildError(
            "cross-compiling needs the `ziglang` package (`pip install ziglang`), "
            f"`python -m ziglang version` failed:\n{proc.stderr.strip()}"
        )
    return proc.stdout.strip()


def target_flags(platform: str) -> list[str]:
    """Flags of every unit for `platform`: the common CFLAGS (no -fPIC for Windows, where
    all code is position-independent and clang rejects the flag for PE targets)."""
    p = PLATFORMS[platform]
    return ["-target", p.zig_target, *(f for f in CFLAGS if not (f == "-fPIC" and p.binary_format == "PE"))]


def _headers(src_dir: Path, name: str, seen: set[str] | None = None) -> set[str]:
    """The local headers `name` includes, transitively (#include "..." found in src_dir)."""
    seen = set() if seen is None else seen
    for inc in _INCLUDE.findall((src_dir / name).read_text(errors="replace")):
        if inc not in seen and (src_dir / inc).is_file():
            seen.add(inc)
            _headers(src_dir, inc, seen)
    return seen


def object_key(src_dir: Path, unit: str, flags: list[str]) -> str:
    """Content key of one object: zig's version, the flags (target included), the unit
    and every local header it includes."""
    digest = hashlib.sha256(repr((zig_version(), flags, unit)).encode())
    for name in [unit, *sorted(_headers(src_dir, unit))]:
        digest.update(name.encode() + b"\0" + (src_dir / name).read_bytes() + b"\0")
    return digest.hexdigest()


def compile_object(src_dir: Path, unit: str, flags: list[str]) -> tuple[Path, str, bool]:
    """(object file in the cache, the compiler's diagnostics, True when it was cached)."""
    key = object_key(src_dir, unit, flags)
    obj = cache_root() / "objects" / key[:2] / f"{key}.o"
    log = obj.with_suffix(".log")
    if obj.is_file() and log.is_file():
        return obj, log.read_text(), True
    obj.parent.mkdir(parents=True, exist_ok=True)
    # unique names, renamed into place: concurrent builds never see half-written entries
    tmp_obj = obj.with_name(f"{key}.{os.getpid()}.{id(flags)}.tmp.o")
    proc = run_zig("cc", *flags, "-I", str(src_dir), "-c", str(src_dir / unit), "-o", str(tmp_obj))
    if proc.returncode != 0:
        tmp_obj.unlink(missing_ok=True)
        raise BuildError(f"zig cc {flags[1]} failed on {unit}:\n{proc.stderr}")
    log.with_suffix(f".{os.getpid()}.tmp").write_text(proc.stderr)
    os.replace(log.with_suffix(f".{os.getpid()}.tmp"), log)
    os.replace(tmp_obj, obj)
    return obj, proc.stderr, False


def link(objects: list[Path], platform: str, out: Path, model_identifier: str) -> str:
    """Link the objects into the stripped shared library `out`; return the linker's diagnostics.
    Mach-O gets an @rpath install name; Windows' import library and debug files stay in
    a scratch folder, only the DLL is kept."""
    p = PLATFORMS[platform]
    # Mach-O: -s keeps the local (static and hidden) symbols, -x drops them too
    extra = ["-Wl,-install_name,@rpath/" + model_identifier + p.suffix, "-Wl,-x"] if p.binary_format == "MACHO" else []
    with tempfile.TemporaryDirectory(prefix="rbfmu_link_") as tmp:
        lib = Path(tmp) / out.name
        # -s: no symbol table or debug info in the shipped binary (the exports stay)
        proc = run_zig("cc", "-target", p.zig_target, "-shared", "-s", *extra, "-o", str(lib), *map(str, objects),
                       "-lm", cwd=Path(tmp))  # fmt: skip
        if proc.returncode != 0:
            raise BuildError(f"linking {out.name} for {platform} failed:\n{proc.stderr}")
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_bytes(lib.read_bytes())
    return proc.stderr


def build_cross(
    src_dir: Path,
    fmi_version: str,
    platforms: list[str],
    binaries: dict[str, Path],
    model_identifier: str,
    unit_list: list[tuple[str, list[str]]] | None = None,
) -> dict[str, tuple[str, int]]:
    """Build the binary of each platform into binaries[platform] (its full file path);
    unit_list: (source, its flags) of another kind of FMU (a controller's), default a scene's.

    Compiles every (platform, unit) pair in parallel (one job per CPU), then links.
    Returns platform -> (diagnostics of its compiles and link, number of objects taken
    from the cache)."""
    unit_list = units(fmi_version) if unit_list is None else unit_list
    jobs = [(p, u, [*target_flags(p), *extra]) for p in platforms for u, extra in unit_list]
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        compiled = list(pool.map(lambda job: compile_object(src_dir, job[1], job[2]), jobs))
        per_platform = {p: [c for (q, _, _), c in zip(jobs, compiled) if q == p] for p in platforms}
        linked = pool.map(
            lambda p: link([obj for obj, _, _ in per_platform[p]], p, binaries[p], model_identifier), platforms
        )
        link_logs = dict(zip(platforms, linked))
    return {
        p: ("".join(diag for _, diag, _ in objs) + link_logs[p], sum(hit for _, _, hit in objs))
        for p, objs in per_platform.items()
    }


def binary_name(model_identifier: str, platform: str) -> str:
    """File name of the shared library of `platform` (FMI: the modelIdentifier + suffix)."""
    return model_identifier + library_suffix(platform)
