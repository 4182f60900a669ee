"""Binaries for every platform in one FMU: architecture and export table of each, runs under qemu-user and wine.

One small scene is built once per session for FMI 3.0 (five platforms) and FMI 2.0
(three) with `platforms="all"` (tests/conftest.py keeps every other FMU native-only).
What cannot run here is inspected with lief: file format, machine, and the exported
functions, which must be exactly the fmi3*/fmi2* functions the standard's header
declares. The aarch64-linux binary runs under qemu-aarch64 and the Windows DLL under
wine when those are installed (Debian packages qemu-user, libc6-arm64-cross, wine),
driven by tests/c/fmi_import_harness.c cross-compiled with Debian's cross gcc
(gcc-aarch64-linux-gnu, gcc-mingw-w64-x86-64) or else zig; otherwise those tests skip and
say why. The Linux binaries must need no glibc above 2.17, and every binary is stripped.
Cost: with the cache of fmu/build/cross_compile.py warm, about 15 s; in a cold cache zig first
compiles its C runtimes (MinGW's for Windows, the glibc and libSystem stubs, compiler-rt:
2-5 min on 2 shared cores), and a wine that has never run creates its prefix (~2 min).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from fmu import cli
from fmu.build.build_fmu import build_fmu
from fmu.build.compile import units
from fmu.build.cross_compile import build_cross
from fmu.build.platforms import PLATFORMS, binary_folder, host_platform, platforms_for, resolve_platforms
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene

from ..harness.import_harness import compile_harness
from ..harness.scenes import write_scene

# A torque-free principal body spinning near its stable major axis 3, one method: the
# smallest generated C, so that the cross builds stay cheap.
SMALL_SCENE = """
name = "spin_small"
description = "Principal body spinning near its major axis (platform tests)."
outputs = ["q", "w_body", "E_kin"]
[body]
principal_moments = [1.0, 2.0, 3.0]
[initial]
w_body = [0.3, 0.2, 2.0]
[experiment]
stop_time = 1.0
step = 0.01
h_max = 0.001
methods = ["rk4"]
"""
# Symbols the Mach-O linker of zig defines in every dylib (the image header and the DSO
# handle): data, not functions, and private to the library under macOS's two-level
# namespace, so they cannot clash with another FMU's.
MACHO_LINKER_SYMBOLS = {"__mh_dylib_header", "___dso_handle"}
STEPS, STEP_SIZE = 100, 0.01


@pytest.fixture(scope="session")
def cross_fmus(tmp_path_factory) -> dict[str, Path]:
    """FMI version -> the small scene's FMU with every platform of that version."""
    out = tmp_path_factory.mktemp("cross")
    scene = load_scene(write_scene(out, SMALL_SCENE, "spin_small"))
    return {v: build_fmu(scene, out, fmi_version=v, platforms="all") for v in ("3", "2")}


@pytest.fixture(scope="session")
def unpacked(cross_fmus, tmp_path_factory) -> dict[str, Path]:
    dirs = {}
    for version, fmu in cross_fmus.items():
        d = tmp_path_factory.mktemp(f"unpacked{version}")
        with zipfile.ZipFile(fmu) as z:
            z.extractall(d)
        dirs[version] = d
    return dirs


def declared_functions(header: Path, version: str) -> set[str]:
    """The functions the standard's header declares (FMI3_Export / FMI2_Export lines)."""
    found = re.findall(rf"^\s*FMI{version}_Export\s+\w+TYPE\s+(fmi{version}\w+);", header.read_text(), re.M)
    return set(found)


# --- platform selection: fast, no compiler ---------------------------------------------


def test_platform_table_matches_fmi_names():
    assert platforms_for(3) == ["x86_64-linux", "aarch64-linux", "x86_64-windows", "x86_64-darwin", "aarch64-darwin"]
    assert [binary_folder(p, 2) for p in platforms_for(2)] == ["linux64", "win64", "darwin64"]
    assert resolve_platforms(None) == [host_platform()]
    assert resolve_platforms("all")[0] == host_platform() and len(resolve_platforms("all")) == 5


@pytest.mark.parametrize(
    ("requested", "version", "needle"),
    [("x86_64-beos", 3, "'x86_64-beos'"), ("aarch64-linux", 2, "FMI 2.0 defines no folder"), ("win64", 3, "win64")],
)
def test_bad_platform_names_the_value_and_what_is_allowed(requested, version, needle):
    with pytest.raises(ModelInputError, match="allowed") as info:
        resolve_platforms(requested, version)
    assert needle in str(info.value)


@pytest.mark.parametrize(
    ("requested", "needle"),
    [("", "no platform named"), (" , ", "no platform named"), ("host,all", "'all' and 'host' stand alone"),
     ("all,x86_64-windows", "'all' and 'host' stand alone")],
)  # fmt: skip
def test_an_empty_or_mixed_platform_list_is_refused(requested, needle):
    # '' built the host alone (the default is all); 'host,all' was refused as "'host' cannot be built"
    with pytest.raises(ModelInputError, match=needle):
        resolve_platforms(requested)


def test_cli_rejects_a_bad_platform(capsys, tmp_path):
    assert cli.main(["build", "heavy_top", "--out", str(tmp_path), "--platforms", "sparc-solaris"]) == 2
    err = capsys.readouterr().err
    assert "sparc-solaris" in err and "x86_64-windows" in err


# --- the cross-built archives -----------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("version", ["3", "2"])
def test_archive_has_every_platform_folder_and_validates(cross_fmus, unpacked, version):
    folders = sorted(p.name for p in (unpacked[version] / "binaries").iterdir())
    expected = {"3": ["aarch64-darwin", "aarch64-linux", "x86_64-darwin", "x86_64-linux", "x86_64-windows"],
                "2": ["darwin64", "linux64", "win64"]}[version]  # fmt: skip
    assert folders == expected
    assert validate_fmu(str(cross_fmus[version])) == []
    # every binary, native and cross, built without a single diagnostic
    stem = cross_fmus[version].name.removesuffix(".fmu")
    assert not (cross_fmus[version].parent / f"{stem}.build.log").exists()


@pytest.mark.slow
@pytest.mark.parametrize(
    ("version", "platform"), [("3", p) for p in platforms_for(3)] + [("2", p) for p in platforms_for(2)]
)
def test_binary_architecture_and_exports(unpacked, version, platform):
    lief = pytest.importorskip("lief")
    lief.logging.disable()
    p = PLATFORMS[platform]
    model_id = "spin_small"
    path = unpacked[version] / "binaries" / binary_folder(platform, version) / f"{model_id}{p.suffix}"
    binary = lief.parse(str(path))
    assert binary is not None, path
    assert binary.format.name == p.binary_format
    header = binary.header
    machine = {"MACHO": "cpu_type", "PE": "machine", "ELF": "machine_type"}[p.binary_format]
    assert getattr(header, machine).name == p.machine
    exported = {e.name.removeprefix(p.symbol_prefix) for e in binary.exported_functions}
    extra = {s.removeprefix(p.symbol_prefix) for s in MACHO_LINKER_SYMBOLS} if p.binary_format == "MACHO" else set()
    declared = declared_functions(unpacked[version] / "sources" / f"fmi{version}Functions.h", version)
    assert len(declared) == (75 if version == "3" else 44)  # functions of fmi3Functions.h / fmi2Functions.h
    assert exported == declared | extra  # every function of the standard, and nothing of CasADi's or ours


# The oldest glibc a Linux binary may need: 2.17 (manylinux2014; RHEL/CentOS 7, Ubuntu 14.04,
# Debian 8), the floor of zig's x86_64-linux-gnu.2.17 / aarch64-linux-gnu.2.17 targets
# (fmu/build/platforms.py). gcc on this machine links pow/log@GLIBC_2.29 and memcpy@GLIBC_2.14.
GLIBC_FLOOR = (2, 17)


def glibc_versions(path: Path) -> list[tuple[int, ...]]:
    """The GLIBC_x.y symbol versions an ELF binary requires (lief's version requirements)."""
    lief = pytest.importorskip("lief")
    lief.logging.disable()
    binary = lief.parse(str(path))
    names = {aux.name for req in binary.symbols_version_requirement for aux in req.get_auxiliary_symbols()}
    return sorted(tuple(int(x) for x in n.removeprefix("GLIBC_").split(".")) for n in names if n.startswith("GLIBC_"))


@pytest.mark.slow
@pytest.mark.parametrize(
    ("version", "platform"), [("3", "x86_64-linux"), ("3", "aarch64-linux"), ("2", "x86_64-linux")]
)
def test_linux_binaries_load_on_glibc_2_17(unpacked, version, platform):
    path = unpacked[version] / "binaries" / binary_folder(platform, version) / "spin_small.so"
    needed = glibc_versions(path)
    assert needed and max(needed) <= GLIBC_FLOOR, f"{path.name} needs {needed}"


@pytest.mark.slow
@pytest.mark.parametrize("version", ["3", "2"])
def test_shipped_binaries_are_stripped(unpacked, version):
    lief = pytest.importorskip("lief")
    lief.logging.disable()
    for platform in platforms_for(version):
        p = PLATFORMS[platform]
        path = unpacked[version] / "binaries" / binary_folder(platform, version) / f"spin_small{p.suffix}"
        binary = lief.parse(str(path))
        if p.binary_format == "ELF":  # no .symtab (local symbols) and no DWARF: only the dynamic exports
            assert not binary.has_section(".symtab") and not binary.has_section(".debug_info"), path
        elif p.binary_format == "MACHO":  # only the exports and the imports in the symbol table
            assert not any(s.name.startswith("_rb_") for s in binary.symbols), path
        else:
            assert not binary.has_debug and not any(s.name == ".debug_info" for s in binary.sections), path


@pytest.mark.slow
def test_a_rebuild_takes_every_object_from_the_cache_and_gives_the_same_binaries(unpacked, tmp_path):
    src = unpacked["3"] / "sources"
    cross = [p for p in platforms_for(3) if p != host_platform()]
    out = {p: tmp_path / p / f"spin_small{PLATFORMS[p].suffix}" for p in cross}
    results = build_cross(src, "3", cross, out, "spin_small")
    for p in cross:
        diagnostics, cached = results[p]
        assert diagnostics == "" and cached == len(units(3)), p
        shipped = unpacked["3"] / "binaries" / p / out[p].name
        if PLATFORMS[p].binary_format == "PE":
            # lld stamps PE files with the link time and a fresh debug GUID (zig passes no
            # option to turn that off): the machine code must still be the same
            lief = pytest.importorskip("lief")
            # keep the parsed binaries alive while their sections are read: `content` is a
            # view into lief's memory, garbage once the binary object is freed
            parsed = [lief.parse(str(f)) for f in (out[p], shipped)]
            text = [bytes(b.get_section(".text").content) for b in parsed]
            assert text[0] == text[1], f"{p}: the code differs after a cached rebuild"
        else:
            assert out[p].read_bytes() == shipped.read_bytes(), f"{p}: the link is not reproducible"


# --- running what runs here: natively, under qemu-user, under wine ----------------------


def _harness_args(unpacked: Path, library: str) -> list[str]:
    md = read_model_description(str(unpacked))
    vrs = [str(v.valueReference) for v in md.modelVariables if v.name.startswith(("q[", "w_body["))]
    return [library, md.guid, str(STEPS), str(STEP_SIZE), *vrs]


def _parse(stdout: str) -> np.ndarray:
    rows = np.array([[float(x) for x in line.split()] for line in stdout.strip().splitlines()])
    assert rows.shape == (STEPS + 1, 8)
    return rows


@pytest.fixture(scope="session")
def native_harness(unpacked, tmp_path_factory) -> Path:
    """The harness compiled with gcc for the host."""
    exe = tmp_path_factory.mktemp("harness") / "harness"
    proc = compile_harness(unpacked["3"] / "sources", None, exe)
    assert proc.returncode == 0, proc.stderr
    return exe


def _native(exe: Path, d: Path, lib: Path) -> np.ndarray:
    proc = subprocess.run([str(exe), *_harness_args(d, str(lib))], capture_output=True, text=True, check=True)
    return _parse(proc.stdout)


@pytest.fixture(scope="session")
def native_run(unpacked, native_harness) -> np.ndarray:
    """The harness on the shipped host binary (zig's, for glibc 2.17): the values the others must match."""
    d = unpacked["3"]
    return _native(native_harness, d, d / "binaries" / host_platform() / "spin_small.so")


@pytest.mark.slow
def test_a_gcc_build_of_the_sources_runs_bit_identical_to_the_shipped_zig_binary(unpacked, native_harness, native_run,
                                                                                 tmp_path):  # fmt: skip
    # the shipped x86_64-linux binary is zig's (clang, glibc 2.17); this machine's gcc, with
    # no flags but -O2, against its own glibc 2.36 libm, must give every bit of it
    d, lib = unpacked["3"], tmp_path / "spin_small.so"
    sources = sorted(str(p) for p in (d / "sources").glob("*.c"))
    subprocess.run(["gcc", "-shared", "-fPIC", "-O2", "-o", str(lib), *sources, "-lm"], check=True)
    assert _native(native_harness, d, lib).tolist() == native_run.tolist()


def _cross_harness(d: Path, platform: str, exe: Path) -> None:
    """Compile the harness for `platform` (tests/harness/import_harness.py: Debian's cross gcc where
    installed, an importer built by another toolchain than the FMU, else zig)."""
    proc = compile_harness(d / "sources", platform, exe)
    assert proc.returncode == 0, proc.stderr


# The Windows run must agree with the native one to the last bits that libm may differ in:
# the FMU's arithmetic is IEEE double with no FMA contraction on every target
# (fmu/c/rbfmu_build.h), so only sin/cos/sqrt-like library calls of wine's ucrtbase can
# round differently (≤ 1 ulp each, ~1e-16
# relative). Over 100 steps of RK4 on a body spinning stably near its major axis such
# differences stay near round-off; 1e-13 (relative to the largest |value|, ~2) leaves a
# margin of ~100 ulp and would still catch any real difference (a wrong method, step or
# ABI mismatch changes the 4th-order result at 1e-8 or more).
RUN_TOLERANCE = 1e-13


@pytest.mark.slow
def test_aarch64_linux_binary_runs_under_qemu(unpacked, native_run, tmp_path):
    qemu, sysroot = shutil.which("qemu-aarch64"), Path("/usr/aarch64-linux-gnu")
    if qemu is None or not (sysroot / "lib").is_dir():
        pytest.skip("qemu-aarch64 (Debian qemu-user) or the aarch64 glibc (libc6-arm64-cross) is not installed")
    d = unpacked["3"]
    exe = tmp_path / "harness_aarch64"
    _cross_harness(d, "aarch64-linux", exe)
    lib = d / "binaries" / "aarch64-linux" / "spin_small.so"
    proc = subprocess.run([qemu, "-L", str(sysroot), str(exe), *_harness_args(d, str(lib))],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    rows = _parse(proc.stdout)
    # bit for bit: no FMA contraction on either (fmu/c/rbfmu_build.h), and glibc's libm on
    # aarch64 rounds sin/cos/sqrt as on x86_64 (measured: 808 of 808 values equal)
    assert rows.tolist() == native_run.tolist()


@pytest.mark.slow
def test_windows_dll_runs_under_wine(unpacked, native_run, tmp_path):
    wine = shutil.which("wine") or shutil.which("wine64")
    if wine is None:
        pytest.skip("wine (Debian package wine) is not installed")
    d = unpacked["3"]
    exe = tmp_path / "harness.exe"
    _cross_harness(d, "x86_64-windows", exe)
    lib = d / "binaries" / "x86_64-windows" / "spin_small.dll"
    env = {**os.environ, "WINEDEBUG": "-all", "WINEDLLOVERRIDES": "mscoree,mshtml="}  # no Mono/Gecko prompts
    proc = subprocess.run([wine, str(exe), *_harness_args(d, "Z:" + str(lib).replace("/", "\\"))],
                          capture_output=True, text=True, timeout=300, env=env)  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = _parse(proc.stdout.replace("\r", ""))
    assert np.max(np.abs(rows - native_run)) <= RUN_TOLERANCE * np.max(np.abs(native_run))
