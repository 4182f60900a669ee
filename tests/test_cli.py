"""The rbfmu command, as a user runs it."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from modelsrc.scene import list_scenes


def rbfmu(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "fmu.cli", *args], capture_output=True, text=True, timeout=300, cwd=cwd
    )


def test_scenes_lists_every_scene():
    proc = rbfmu("scenes")
    assert proc.returncode == 0
    for name in list_scenes():
        assert name in proc.stdout


def test_run_writes_csv_plot_and_summary(tmp_path):
    csv, png = tmp_path / "r.csv", tmp_path / "r.png"
    proc = rbfmu(
        "run",
        "symmetric_free",
        "--stop-time",
        "1",
        "--step",
        "0.05",
        "--set",
        "w_body[3]=3",
        "--csv",
        str(csv),
        "--plot",
        str(png),
        "--out",
        str(tmp_path),
    )
    assert proc.returncode == 0, proc.stderr
    assert "symmetric_free" in proc.stdout and "E drift" in proc.stdout
    data = np.genfromtxt(csv, delimiter=",", names=True)
    assert data["time"][-1] == 1.0 and len(data) == 21
    assert np.allclose(data["w_body3"], 3.0)  # the --set start value was used; ω3 stays constant
    assert png.stat().st_size > 10_000


def test_build_writes_fmu(tmp_path):
    proc = rbfmu("build", "heavy_top", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "heavy_top.fmu").is_file()
