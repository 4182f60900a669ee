"""`rbfmu controllers` and `rbfmu build` of a controller file (modelsrc/controllers/), through the command line."""

from __future__ import annotations

import zipfile

import pytest

from modelsrc.controllers.controller_file import list_controllers

from .test_cli import rbfmu


def test_controllers_lists_every_shipped_controller_with_its_plant():
    proc = rbfmu("controllers")
    assert proc.returncode == 0, proc.stderr
    assert list_controllers() == ["attitude_pd", "attitude_torque_pd", "quadrotor_hover"]
    shipped = (("attitude_pd", "reaction_wheel_slew"), ("attitude_torque_pd", "torque_driven"),
               ("quadrotor_hover", "quadrotor_motors"))  # fmt: skip
    for name, plant in shipped:
        assert any(line.startswith(name) and f"plant {plant}" in line for line in proc.stdout.splitlines()), proc.stdout


@pytest.mark.slow
def test_build_makes_a_controller_fmu_by_name_and_by_path(tmp_path):
    """By name (FMI 2.0) and by the file's path (FMI 3.0), host binary only: Co-Simulation only, the
    sampled-data layer and the generated law in sources/."""
    proc = rbfmu("build", "attitude_pd", "--fmi-version", "2", "--platforms", "host", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    with zipfile.ZipFile(tmp_path / "attitude_pd_fmi2.fmu") as z:
        names = z.namelist()
        md = z.read("modelDescription.xml").decode()
    assert "binaries/linux64/attitude_pd.so" in names and "sources/ctrl_funcs.c" in names
    assert "<CoSimulation" in md and "<ModelExchange" not in md
    path = "modelsrc/controllers/quadrotor_hover.toml"
    proc = rbfmu("build", path, "--platforms", "host", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "quadrotor_hover.fmu").is_file()


def test_build_of_an_unknown_name_lists_scenes_and_controllers():
    proc = rbfmu("build", "no_such_thing")
    assert proc.returncode == 2
    assert "unknown scene or controller 'no_such_thing'" in proc.stderr and "controllers: attitude_pd" in proc.stderr
