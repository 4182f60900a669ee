"""Licence, version and changelog: what a built FMU and the package declare (docs/licensing.md, CHANGELOG.md)."""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
import zipfile
from importlib import metadata
from pathlib import Path

import pytest
from fmpy import read_model_description

import fmu
from fmu.build.licensing import LICENSE_MEMBER, PLATFORM_NOTICES, archive_license, package_license

REPO = Path(__file__).resolve().parent.parent.parent


def _declared(path: Path, fmi_version: str) -> None:
    """The modelDescription's version, copyright and license, and the licence file they point to."""
    md = read_model_description(str(path))
    assert md.version == fmu.__version__
    assert md.generationTool.startswith(f"rbfmu {fmu.__version__} ")  # said 0.1.0 under package 0.2.0
    assert md.copyright == "Copyright (c) 2026, the rbfmu authors"
    assert md.license == f"BSD-2-Clause; see {LICENSE_MEMBER[fmi_version]}"
    with zipfile.ZipFile(path) as z:
        text = z.read(LICENSE_MEMBER[fmi_version]).decode()
        index = z.read("documentation/index.html").decode()
    relative = LICENSE_MEMBER[fmi_version].removeprefix("documentation/")
    assert f"Licence: BSD-2-Clause (<a href='{relative}'>" in index
    assert (REPO / "LICENSE").read_text() in text  # the whole BSD-2-Clause text, not a reference to it
    assert f"rbfmu {fmu.__version__}, FMI {fmi_version}.0" in text
    # a host-only build holds no third-party code, so no third-party notice
    assert "Notice 1" not in text and "mingw-w64" not in text


def test_fmi3_archive_declares_licence_and_version(fmus):
    _declared(fmus["skewed_bar"], "3")


def test_fmi2_archive_declares_licence_and_version(fmi2_fmus):
    _declared(fmi2_fmus["skewed_bar"], "2")


def test_windows_binary_brings_its_third_party_notices():
    """The DLL holds mingw-w64 start-up objects and zig's compiler_rt (docs/licensing.md):
    their notices are in the licence file exactly when the archive carries the DLL."""
    text = archive_license("3", ["x86_64-linux", "x86_64-windows", "aarch64-darwin"])
    for name, what in PLATFORM_NOTICES["x86_64-windows"]:
        assert what in text
        assert package_license(name).strip() in text
    assert "Notice 1" not in archive_license("3", ["x86_64-linux", "aarch64-linux", "x86_64-darwin"])


def test_licence_texts_in_the_package_match_their_sources():
    """rbfmu's licence in the package equals the repository's LICENSE; the third-party
    notices equal the files of the installed ziglang whose code the DLL holds, so a zig
    upgrade that changes them fails here."""
    assert package_license() == (REPO / "LICENSE").read_text()
    zig = {str(f): f for f in metadata.files("ziglang") or []}
    sources = {
        "zig.txt": "ziglang/LICENSE",
        "musl.txt": "ziglang/lib/libc/musl/COPYRIGHT",
        "mingw-w64.txt": "ziglang/lib/libc/mingw/COPYING",
    }
    for name, source in sources.items():
        assert package_license(name) == zig[source].read_text(), name


def test_pyproject_declares_the_licence_and_reads_the_version_from_the_package():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    assert project["project"]["license"] == "BSD-2-Clause"
    assert project["project"]["license-files"] == ["LICENSE"]
    assert "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "fmu.__version__"}
    assert "licenses/*.txt" in project["tool"]["setuptools"]["package-data"]["fmu.build"]


def test_version_option_prints_the_package_and_tool_versions():
    proc = subprocess.run(
        [sys.executable, "-m", "fmu.cli", "--version"], capture_output=True, text=True, cwd=REPO, timeout=60
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0] == f"rbfmu {fmu.__version__}"
    assert f"CasADi {metadata.version('casadi')} " in proc.stdout
    assert f"fmpy {metadata.version('fmpy')} " in proc.stdout
    zig = subprocess.run([sys.executable, "-m", "ziglang", "version"], capture_output=True, text=True, timeout=60)
    assert f"zig {zig.stdout.strip()} (ziglang {metadata.version('ziglang')};" in proc.stdout


def test_changelog_newest_entry_is_the_package_version():
    text = (REPO / "CHANGELOG.md").read_text()
    entries = re.findall(r"^## \[([^\]]+)\]", text, re.M)
    assert entries, "no '## [version]' entries"
    assert entries[0] == fmu.__version__
    assert "Unreleased" not in entries
    # keep-a-changelog: newest first, each with a date
    dated = re.findall(r"^## \[([^\]]+)\] - (\d{4}-\d{2}-\d{2})$", text, re.M)
    assert [v for v, _ in dated] == entries
    versions = [tuple(int(x) for x in v.split(".")) for v in entries]
    assert versions == sorted(versions, reverse=True)


@pytest.mark.parametrize("page", ["README.md", "docs/user_guide.md"])
def test_licensing_page_is_linked(page):
    assert "docs/licensing.md" in (REPO / page).read_text() or "licensing.md" in (REPO / page).read_text()
