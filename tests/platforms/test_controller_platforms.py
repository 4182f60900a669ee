"""A controller FMU carries every platform's binary like a scene's: folders, validation, export tables, glibc floor.

attitude_pd is built once per module with `platforms="all"` for FMI 3.0 (five platforms) and 2.0
(three); the checks are those of tests/platforms/test_platforms.py for a scene (lief reads the
binaries that cannot run here). Cost: ~15 s with the zig object cache warm, minutes cold.
"""

from __future__ import annotations

import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy.validation import validate_fmu

from fmu.build.controller_build import build_controller
from fmu.build.platforms import PLATFORMS, binary_folder, platforms_for

from ..harness.slave import Slave
from .test_platforms import GLIBC_FLOOR, MACHO_LINKER_SYMBOLS, declared_functions, glibc_versions

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def unpacked_controllers(tmp_path_factory) -> dict[str, tuple[Path, Path]]:
    """FMI version -> (the archive, its unpacked folder)."""
    out = tmp_path_factory.mktemp("ctrl_cross")
    found = {}
    for v in ("3", "2"):
        fmu = build_controller("attitude_pd", out, fmi_version=v, platforms="all")
        d = out / f"unpacked{v}"
        with zipfile.ZipFile(fmu) as z:
            z.extractall(d)
        found[v] = (fmu, d)
    return found


@pytest.mark.parametrize("version", ["3", "2"])
def test_the_archive_has_every_platform_and_validates(unpacked_controllers, version):
    fmu, d = unpacked_controllers[version]
    assert sorted(p.name for p in (d / "binaries").iterdir()) == sorted(
        binary_folder(p, version) for p in platforms_for(version)
    )
    assert validate_fmu(str(fmu)) == []
    assert not fmu.with_name(fmu.name.removesuffix(".fmu") + ".build.log").exists()  # no diagnostics


@pytest.mark.parametrize(
    ("version", "platform"), [("3", p) for p in platforms_for(3)] + [("2", p) for p in platforms_for(2)]
)
def test_each_binary_exports_exactly_the_standards_functions(unpacked_controllers, version, platform):
    lief = pytest.importorskip("lief")
    lief.logging.disable()
    p = PLATFORMS[platform]
    d = unpacked_controllers[version][1]
    binary = lief.parse(str(d / "binaries" / binary_folder(platform, version) / f"attitude_pd{p.suffix}"))
    assert binary is not None and binary.format.name == p.binary_format
    exported = {e.name.removeprefix(p.symbol_prefix) for e in binary.exported_functions}
    extra = {s.removeprefix(p.symbol_prefix) for s in MACHO_LINKER_SYMBOLS} if p.binary_format == "MACHO" else set()
    assert exported == declared_functions(d / "sources" / f"fmi{version}Functions.h", version) | extra
    if p.binary_format == "ELF":
        assert (
            max(glibc_versions(d / "binaries" / binary_folder(platform, version) / f"attitude_pd{p.suffix}"))
            <= GLIBC_FLOOR
        )


def test_the_source_fmu_rebuilds_with_cmake_and_gives_the_same_outputs(tmp_path):
    """sources/CMakeLists.txt of a controller FMU (FMI 2.0, host binary removed): cmake builds and
    installs the binary, and the rebuilt FMU gives the shipped binary's outputs bit for bit."""
    cmake = shutil.which("cmake")
    if cmake is None:
        pytest.skip("cmake is not installed: the source build cannot be checked here")
    fmu = build_controller("attitude_pd", tmp_path, fmi_version=2)
    d = tmp_path / "src_fmu"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(d)
    shutil.rmtree(d / "binaries")
    for args in (
        ["-S", d / "sources", "-B", tmp_path / "b"],
        ["--build", tmp_path / "b"],
        ["--install", tmp_path / "b"],
    ):
        proc = subprocess.run([cmake, *map(str, args)], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        assert "warning" not in proc.stdout.lower() + proc.stderr.lower()
    rebuilt = tmp_path / "rebuilt.fmu"
    with zipfile.ZipFile(rebuilt, "w") as z:
        for f in sorted(d.rglob("*")):
            if f.is_file():
                z.write(f, f.relative_to(d).as_posix())
    values = {"q[1]": 0.9, "q[2]": 0.1, "q[3]": -0.2, "q[4]": 0.3, "w_body[2]": 0.05}
    outs = []
    for path in (fmu, rebuilt):
        s = Slave(path, 2)
        s.set(values)
        outs.append(s.get(["u_x", "u_y", "u_z"]))
        s.close()
    assert np.array_equal(outs[0], outs[1]) and np.any(outs[0] != 0.0)
