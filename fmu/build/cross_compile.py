"""Cross-compilation of an FMU binary with `zig cc` for other platforms, with a content-keyed object cache.

`zig cc -target T` (the `ziglang` package, pinned in constraints.txt) is clang with the C
library headers and import stubs of every target, so the FMU's C builds for Windows,
macOS and ARM Linux on this machine with no system packages. Each object file comes from
the content-keyed cache of fmu/build/object_cache.py (keyed by zig's version and the target
among the rest), so a rebuild of the same scene only links. zig's own cache (its C runtimes,
e.g. MinGW's for Windows, built once in minutes) lives under the same directory.
"""

from __future__ import annotations

import functools
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from .compile import CFLAGS, BuildError, units
from .object_cache import CACHE_ENV as CACHE_ENV  # re-exported for the fmu.cross_compile alias (CHANGELOG.md)
from .object_cache import cache_root, cached_object, content_key
from .platforms import PLATFORMS, library_suffix


def run_zig(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """Run `zig ARGS` of the ziglang package. Its global cache (each target's C runtime,
    built once, tens of MB) is kept under cache_root(); its local cache, where zig would keep
    a copy of every object and library it makes, is a scratch folder removed after the call:
    the objects are kept once, in the size-limited object cache (fmu/build/object_cache.py)."""
    with tempfile.TemporaryDirectory(prefix="rbfmu_zig_") as local:
        env = {**os.environ, "ZIG_GLOBAL_CACHE_DIR": str(cache_root() / "zig"), "ZIG_LOCAL_CACHE_DIR": local}
        return subprocess.run(
            [sys.executable, "-m", "ziglang", *args], capture_output=True, text=True, env=env, cwd=cwd
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


def object_key(src_dir: Path, unit: str, flags: list[str]) -> str:
    """Content key of one object: zig's version, the flags (target included), the unit
    and every local header it includes (fmu/build/object_cache.py)."""
    return content_key(src_dir, unit, f"zig {zig_version()}", flags)


def compile_object(src_dir: Path, unit: str, flags: list[str]) -> tuple[Path, str, bool]:
    """(object file in the cache, the compiler's diagnostics, True when it was cached)."""

    def compile_to(obj: Path) -> str:
        proc = run_zig("cc", *flags, "-I", str(src_dir), "-c", str(src_dir / unit), "-o", str(obj))
        if proc.returncode != 0:
            raise BuildError(f"zig cc {flags[1]} failed on {unit}:\n{proc.stderr}")
        return proc.stderr

    return cached_object(object_key(src_dir, unit, flags), compile_to)


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
