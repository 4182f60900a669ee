"""The binary platforms an FMU can carry: FMI 3.0 tuple, FMI 2.0 folder, cross-compiler target, file format.

This table is the one source of these facts: the build (fmu/build/build_fmu.py,
fmu/build/cross_compile.py), the `rbfmu build --platforms` option, the tests that read each
binary's architecture and export table (tests/platforms/test_platforms.py) and the docs read it.
A host-only build compiles with gcc (for this machine's C library); a multi-platform
build compiles every binary, the host's too, with `zig cc` (the `ziglang` package), which
brings the C library headers and import stubs of each target and so pins the oldest C
library a binary needs (the zig_target below).
"""

from __future__ import annotations

import platform as _platform
from dataclasses import dataclass

from modelsrc.errors import ModelInputError


@dataclass(frozen=True)
class Platform:
    """One binary platform of an FMU.

    name: the FMI 3.0 platform tuple, also the binaries/ folder of FMI 3.0 archives
    (FMI 3.0 §2.5.1.1); fmi2_folder: the FMI 2.0 folder (FMI 2.0 §2.3), None where FMI
    2.0 defines none; zig_target: `zig cc -target` value, pinning the oldest C library
    and OS the binary needs (glibc 2.17 as manylinux2014, macOS 11, the first with
    Apple silicon); suffix: the shared-library file name ending; binary_format and
    machine: what lief reports for it (`lief.Binary.format`, the ELF/PE machine or
    Mach-O CPU type name), read by the tests.
    """

    name: str
    fmi2_folder: str | None
    zig_target: str
    suffix: str
    binary_format: str
    machine: str
    symbol_prefix: str = ""  # Mach-O prefixes C symbols with "_"


PLATFORMS: dict[str, Platform] = {
    p.name: p
    for p in (
        Platform("x86_64-linux", "linux64", "x86_64-linux-gnu.2.17", ".so", "ELF", "X86_64"),
        Platform("aarch64-linux", None, "aarch64-linux-gnu.2.17", ".so", "ELF", "AARCH64"),
        Platform("x86_64-windows", "win64", "x86_64-windows-gnu", ".dll", "PE", "AMD64"),
        Platform("x86_64-darwin", "darwin64", "x86_64-macos.11.0", ".dylib", "MACHO", "X86_64", "_"),
        Platform("aarch64-darwin", None, "aarch64-macos.11.0", ".dylib", "MACHO", "ARM64", "_"),
    )
}


def host_platform() -> str:
    """The FMI 3.0 tuple of this machine (what gcc builds): x86_64-linux, aarch64-darwin, ..."""
    arch = {"AMD64": "x86_64", "arm64": "aarch64"}.get(_platform.machine(), _platform.machine())
    system = {"darwin": "darwin", "windows": "windows"}.get(_platform.system().lower(), _platform.system().lower())
    return f"{arch}-{system}"


def binary_folder(name: str, fmi_version: str | int = 3) -> str:
    """The binaries/ folder of platform `name` in an FMI 3.0 or 2.0 archive."""
    if str(fmi_version) == "3":
        return name
    known = PLATFORMS.get(name)
    if known is not None and known.fmi2_folder:
        return known.fmi2_folder
    arch, _, system = name.partition("-")
    folder = {"linux": "linux", "darwin": "darwin", "windows": "win"}.get(system, system)
    return folder + ("64" if arch in ("x86_64", "aarch64") else "32")


def library_suffix(name: str) -> str:
    """.so, .dll or .dylib: how the shared library of platform `name` ends."""
    known = PLATFORMS.get(name)
    if known is not None:
        return known.suffix
    return {"windows": ".dll", "darwin": ".dylib"}.get(name.partition("-")[2], ".so")


def platforms_for(fmi_version: str | int) -> list[str]:
    """Every platform an archive of this FMI version can carry (FMI 2.0 names no ARM folders)."""
    return [p.name for p in PLATFORMS.values() if str(fmi_version) == "3" or p.fmi2_folder]


def resolve_platforms(requested: str | list[str] | tuple[str, ...] | None, fmi_version: str | int = 3) -> list[str]:
    """The platforms to build, host first: None or "host" -> the host only; "all" -> every
    platform of the FMI version; a list or comma-separated names -> those, plus the host,
    whose binary is always built (the build runs it). ModelInputError names a bad one
    and what is allowed."""
    host = host_platform()
    if requested is None:
        return [host]
    names = requested.split(",") if isinstance(requested, str) else list(requested)
    names = [n.strip() for n in names if n.strip()]
    allowed = platforms_for(fmi_version)
    if not names:  # an empty value would build the host alone, whatever the default asked
        raise ModelInputError(f"--platforms {requested!r}: no platform named; give 'all', 'host' or some of "
                              f"{', '.join(allowed)}")  # fmt: skip
    if names == ["all"]:
        names = allowed
    elif names == ["host"]:
        names = []
    elif {"all", "host"} & set(names):
        raise ModelInputError(f"--platforms {requested!r}: 'all' and 'host' stand alone; give one of them, or a "
                              f"list of {', '.join(allowed)}")  # fmt: skip
    bad = [n for n in names if n not in allowed]
    if bad:
        why = " (FMI 2.0 defines no folder for it)" if str(fmi_version) == "2" and bad[0] in PLATFORMS else ""
        raise ModelInputError(
            f"platform {bad[0]!r} cannot be built{why}; allowed for FMI {fmi_version}.0: "
            f"{', '.join(allowed)}, 'all' or 'host'"
        )
    return [host, *(n for n in dict.fromkeys(names) if n != host)]
