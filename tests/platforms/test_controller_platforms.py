"""A controller FMU carries every platform's binary like a scene's: folders, validation, export tables, glibc floor.

attitude_pd is built once per module with `platforms="all"` for FMI 3.0 (five platforms) and 2.0
(three); the checks are those of tests/platforms/test_platforms.py for a scene (lief reads the
binaries that cannot run here). Cost: ~15 s with the zig object cache warm, minutes cold.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest
from fmpy.validation import validate_fmu

from fmu.build.controller_build import build_controller
from fmu.build.platforms import PLATFORMS, binary_folder, platforms_for

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
