"""The C build of an FMU binary: its translation units, the compiler flags, and gcc for a host-only build.

Every binary of an FMU, native or cross-compiled (fmu/build/cross_compile.py) or rebuilt from
the source FMU's CMakeLists.txt (fmu/build/source_fmu.py), is made of the same units with the
same warning rules: the hand-written layer under -Werror, the generated file with the
one warning CasADi's code generator always trips switched off.
"""

from __future__ import annotations

import functools
import subprocess
import tempfile
from pathlib import Path

from .build_error import BuildError as BuildError  # raised here; importers take it from this module too
from .object_cache import cached_object, content_key

C_DIR = Path(__file__).resolve().parent.parent / "c"
# The hand-written, version-independent core (docs/fmi_layer.md); every FMU carries all of it.
CORE_SOURCES = (
    "rbfmu_core.c",
    "rbfmu_dostep.c",
    "rbfmu_step.c",
    "rbfmu_control.c",
    "rbfmu_inputs.c",
    "rbfmu_budget.c",
    "rbfmu_exchange.c",
    "rbfmu_snapshot.c",
)
CORE = (*CORE_SOURCES, "rbfmu_core.h", "rbfmu_build.h")
# The API files of each FMI version over the core (FMI 3.0: the API, and the functions it does not provide).
ADAPTERS = {"3": ("rbfmu_fmi3.c", "rbfmu_fmi3_absent.c"), "2": ("rbfmu_fmi2.c",)}
GENERATED_SOURCE = "model_funcs.c"
# -ffp-contract=off: no fused multiply-add contraction, which clang (zig cc) does by
# default on aarch64; every platform then rounds each operation alike, and the results
# differ across platforms only where their libm does (docs/importing.md §Platforms). The
# sources carry it and -fvisibility=hidden themselves (c/rbfmu_build.h), for builds with
# other flags; here they stay as flags too.
CFLAGS = ["-O2", "-std=c99", "-fPIC", "-fvisibility=hidden", "-ffp-contract=off", "-Wall", "-Wextra"]
HANDWRITTEN_EXTRA = ["-Werror"]
# The hand-written layer must be warning-free (-Werror). CasADi's generated functions
# have a fixed signature (arg, res, iw, w, mem) whose unused arguments trip
# -Wunused-parameter, a known property of its code generator (casadi issue #2014);
# that single warning is disabled for the generated file only, all others stay on.
GENERATED_EXTRA = ["-Wno-unused-parameter"]


def c_sources(fmi_version: str | int = 3) -> list[str]:
    """The C files of an FMU's binary, as named in its sources/ folder: the API adapter of
    the FMI version, the core, and the generated model functions."""
    return [*ADAPTERS[str(fmi_version)], *CORE_SOURCES, GENERATED_SOURCE]


def units(fmi_version: str | int = 3) -> list[tuple[str, list[str]]]:
    """(source file, its extra flags) of every translation unit of the binary."""
    return [(src, GENERATED_EXTRA if src == GENERATED_SOURCE else HANDWRITTEN_EXTRA) for src in c_sources(fmi_version)]


@functools.cache
def gcc_version() -> str:
    """gcc's identity for the object cache (`gcc --version`'s first line and its target,
    `gcc -dumpmachine`); BuildError when there is no gcc on PATH."""
    try:
        version = subprocess.run(["gcc", "--version"], capture_output=True, text=True)
        machine = subprocess.run(["gcc", "-dumpmachine"], capture_output=True, text=True)
    except OSError as exc:
        raise BuildError(f"the host build needs gcc on PATH: {exc}") from exc
    if version.returncode != 0 or machine.returncode != 0:
        raise BuildError(f"`gcc --version` failed: {(version.stderr + machine.stderr).strip()}")
    return f"{version.stdout.splitlines()[0]} {machine.stdout.strip()}"


def compile_units(
    src_dir: Path,
    scratch: Path,
    fmi_version: str | int,
    extra_flags: list[str],
    unit_list: list[tuple[str, list[str]]] | None = None,
) -> tuple[list[Path], str]:
    """(object files, gcc's diagnostics) of every unit of the binary (`units`, or unit_list:
    (source, its flags) of another kind of FMU, a controller's), each with CFLAGS, its own
    flags and extra_flags. Objects come from the content-keyed cache (fmu/build/object_cache.py)
    when the same unit, headers, flags and gcc were compiled before. Debug builds (-g) are
    compiled into `scratch` and not cached: their objects record the source's path, so they
    would be keyed by a temporary folder and never be found again."""
    objs, diagnostics = [], ""
    for src, flags in units(fmi_version) if unit_list is None else unit_list:
        unit_flags = [*CFLAGS, *flags, *extra_flags]

        def compile_to(obj: Path, src: str = src, unit_flags: list[str] = unit_flags) -> str:
            proc = subprocess.run(
                ["gcc", *unit_flags, "-I", str(src_dir), "-c", str(src_dir / src), "-o", str(obj)],
                capture_output=True,
                text=True,
            )
            if proc.returncode != 0:
                raise BuildError(f"gcc failed on {src}:\n{proc.stderr}")
            return proc.stderr

        if any(f.startswith("-g") for f in unit_flags):
            obj = scratch / f"{src}.o"
            diagnostics += compile_to(obj)
        else:
            obj, unit_diagnostics, _ = cached_object(
                content_key(src_dir, src, f"gcc {gcc_version()}", unit_flags), compile_to
            )
            diagnostics += unit_diagnostics
        objs.append(obj)
    return objs, diagnostics


def compile_native(
    src_dir: Path,
    out: Path,
    fmi_version: str,
    extra_flags: list[str],
    unit_list: list[tuple[str, list[str]]] | None = None,
) -> str:
    """Compile (`compile_units`) and link the host's (stripped) binary with gcc; return gcc's
    diagnostics (empty when warning-free). extra_flags go to every compile and the link (e.g.
    sanitizers); unit_list: (source, its flags) of another kind of FMU (a controller's),
    default a scene's."""
    with tempfile.TemporaryDirectory(prefix="rbfmu_objects_") as scratch:
        objs, diagnostics = compile_units(src_dir, Path(scratch), fmi_version, extra_flags, unit_list)
        # stripped like the cross-built binaries (fmu/build/cross_compile.py), unless built with extra
        # flags (sanitizers, -g): their reports want the symbols
        strip = [] if extra_flags else ["-s"]
        link = ["gcc", "-shared", *strip, *extra_flags, "-o", str(out), *map(str, objs), "-lm"]
        proc = subprocess.run(link, capture_output=True, text=True)
    if proc.returncode != 0:
        raise BuildError(f"linking {out.name} failed:\n{proc.stderr}")
    return diagnostics + proc.stderr
