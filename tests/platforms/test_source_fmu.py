"""The source FMU: every archive's sources/ rebuilds the binary with CMake or fmpy, bit-identical in fmpy.

An FMU is unpacked, its binaries/ deleted, and the binary rebuilt for this machine from
sources/ alone: with the archive's own CMakeLists.txt (cmake from PyPI), and with fmpy's
source-FMU compilation (`fmpy.build.build_platform_binary`, which reads
buildDescription.xml in FMI 3.0 and the modelDescription's SourceFiles in FMI 2.0).
The rebuilt FMU must give the same results as the shipped one, bit for bit: the same C,
the same IEEE arithmetic (no -ffast-math, no FMA contraction on x86_64) and the same
libm leave no room for a difference.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from fmu.build.build_fmu import platform_tuple
from fmu.build.compile import c_sources
from fmu.build.platforms import library_suffix

CMAKE = shutil.which("cmake", path=str(Path(sys.executable).parent)) or shutil.which("cmake")


def _unpack_without_binaries(fmu: Path, dest: Path) -> Path:
    with zipfile.ZipFile(fmu) as z:
        z.extractall(dest)
    shutil.rmtree(dest / "binaries")
    return dest


def _results(fmu_dir_or_file: Path) -> np.ndarray:
    """Every output of a Co-Simulation run of the default experiment, as one array."""
    md = read_model_description(str(fmu_dir_or_file))
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    res = simulate_fmu(str(fmu_dir_or_file), fmi_type="CoSimulation", output=outputs)
    return np.column_stack([res[name] for name in outputs])


def _fmu(version: str, fmus, fmi2_fmus) -> Path:
    return fmus["skewed_bar"] if version == "3" else fmi2_fmus["skewed_bar"]


def _library(d: Path, version: str) -> Path:
    return d / "binaries" / platform_tuple(version) / ("skewed_bar" + library_suffix(platform_tuple("3")))


@pytest.mark.slow
@pytest.mark.parametrize("version", ["3", "2"])
def test_cmake_rebuild_gives_bit_identical_results(fmus, fmi2_fmus, version, tmp_path):
    if CMAKE is None:
        pytest.skip("cmake is not installed (pip install cmake)")
    fmu = _fmu(version, fmus, fmi2_fmus)
    d = _unpack_without_binaries(fmu, tmp_path / "fmu")
    text = (d / "sources" / "CMakeLists.txt").read_text()
    assert all(f in text for f in c_sources(version))  # the same files as buildDescription.xml
    for args in (["-S", str(d / "sources"), "-B", str(tmp_path / "build")],
                 ["--build", str(tmp_path / "build"), "--config", "Release"],
                 ["--install", str(tmp_path / "build"), "--config", "Release"]):  # fmt: skip
        proc = subprocess.run([CMAKE, *args], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        assert "warning" not in proc.stderr.lower(), proc.stderr
    assert _library(d, version).is_file()
    assert np.array_equal(_results(d), _results(fmu))


@pytest.mark.slow
@pytest.mark.parametrize("version", ["3", "2"])
def test_fmpy_source_compilation_gives_bit_identical_results(fmus, fmi2_fmus, version, tmp_path, monkeypatch):
    if CMAKE is None:
        pytest.skip("cmake is not installed (pip install cmake); fmpy's build runs it")
    from fmpy.build import build_platform_binary

    fmu = _fmu(version, fmus, fmi2_fmus)
    d = _unpack_without_binaries(fmu, tmp_path / "fmu")
    md = read_model_description(str(d))
    assert md.buildConfigurations[0].sourceFileSets[0].sourceFiles == c_sources(version)
    monkeypatch.setenv("PATH", str(Path(CMAKE).parent) + os.pathsep + os.environ["PATH"])  # fmpy runs `cmake`
    (tmp_path / "build").mkdir()
    build_platform_binary(d, tmp_path / "build")
    assert _library(d, version).is_file()
    assert np.array_equal(_results(d), _results(fmu))
