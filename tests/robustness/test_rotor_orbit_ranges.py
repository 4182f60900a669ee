"""Rotors, orbits and the central field under hostile values: each is refused with one line naming it and its range.

Issue 39, items 1, 2, 5, 6, 7, 8 and the propeller constants: a rotor start rate whose
square overflows, a centre of mass at the central body, a value the run's driver would
replace, an orbit angle too large to advance, a rotor inertia below the floor of the
mass and inertia, propeller constants beyond the parameter range. The scene-file cases
run no compiler; the FMU cases use the shared fixed-step FMUs of tests/harness.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fmu.cli import main
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene

from ..harness.fmi3_ctypes import OK, shared_library
from ..harness.misuse_helpers import refused_at_exit_initialization

SCENES = Path(__file__).resolve().parent.parent.parent / "modelsrc" / "scenes"


def _scene(tmp_path: Path, shipped: str, old: str, new: str) -> Path:
    """The shipped scene with one line changed, under the name `custom`."""
    text = (SCENES / f"{shipped}.toml").read_text()
    assert old in text
    text = text.replace(old, new).replace(f'name = "{shipped}"', 'name = "custom"')
    path = tmp_path / "custom.toml"
    path.write_text(text)
    return path


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.startswith("rbfmu: error: ") and "\n" not in err, err
    return err


def test_rotor_start_rate_whose_square_overflows_is_refused_before_the_build(tmp_path, capsys):
    """Item 1. Before: a raw OverflowError from model_functions (the nominal squared)."""
    scene = _scene(tmp_path, "dual_spin", "Omega_wheel = 100.0", "Omega_wheel = 1e300")
    load_scene(scene)  # a finite number: the scene is valid, its FMU's nominals are not
    out = tmp_path / "out"
    assert main(["build", str(scene), "--out", str(out), "--platforms", "host"]) == 2
    err = _one_error_line(capsys)
    assert re.search(r"\|initial.Omega_wheel\| overflows double precision \(1e\+300\)", err), err
    assert "below 1e154" in err


@pytest.mark.parametrize("x", ["1e-160", "1e-100", "0.5"])
def test_centre_of_mass_at_the_central_body_is_refused_at_load(tmp_path, x):
    """Item 2. Before: 1e-160 gave a ZeroDivisionError traceback (|x0|^3 underflowed to 0).
    eccentric_orbit's size sqrt(tr I / m) = sqrt(1500 / 500) = 1.73 m: 0.5 m is inside it."""
    scene = _scene(tmp_path, "eccentric_orbit", "x_cm = [6300000.0, 0.0, 0.0]", f"x_cm = [{x}, 0.0, 0.0]")
    with pytest.raises(ModelInputError) as e:
        load_scene(scene)
    msg = str(e.value)
    assert "field 'initial.x_cm'" in msg and "the body is at the central body" in msg and "\n" not in msg
    assert f"|x_cm| = {float(x):g} is not above the body's size sqrt(tr I / m) = 1.73205 m" in msg


@pytest.mark.parametrize(
    "args",
    [
        ["run", "quadrotor", "--set", "Omega_dot_p1=5"],
        ["sweep", "quadrotor", "--param", "Omega_dot_p1=0:1e300:2"],
        ["sweep", "quadrotor", "--sample", "Omega_dot_p2=uniform(0, 5)", "--samples", "2"],
        ["sweep", "quadrotor", "--param", "w_body[1]=0:1:2", "--set", "Omega_dot_p3=1"],
    ],
    ids=["run_set", "sweep_param", "sweep_sample", "sweep_set"],
)
def test_a_value_the_driver_replaces_is_not_settable(tmp_path, monkeypatch, capsys, args):
    """Item 5. Before: accepted and silently replaced by the derivative of the Omega
    schedule (runs with 0, 5 and 1e300 were bit-identical). Refused before any build."""
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    err = _one_error_line(capsys)
    name = re.search(r"Omega_dot_p\d", " ".join(args)).group(0)
    assert f"{name} cannot be set: the run derives it from the schedule of Omega_{name[-2:]}" in err, err
    assert not list(tmp_path.iterdir())  # nothing built


def test_rotor_inertia_below_the_floor_is_refused(tmp_path):
    """Item 7, scene file. Before: J = 5e-324 loaded and the first doStep failed unnamed."""
    scene = _scene(tmp_path, "dual_spin", "J = 1.0 ", "J = 5e-324 ")
    with pytest.raises(ModelInputError, match=r"field 'rotors.wheel.J': must be in \[1e-100, 1e\+100\].*5e-324"):
        load_scene(scene)


@pytest.mark.parametrize(
    "old, new, field",
    [
        ("k_f = 1.5e-5", "k_f = 1e300", "rotors.p1.k_f"),
        ("k_m = 2.4e-7", "k_m = 1e300", "rotors.p1.k_m"),
        ("position = [0.2, 0.0, 0.0]", "position = [1e300, 0.0, 0.0]", "rotors.p1.position[1]"),
    ],
)
def test_propeller_constants_beyond_the_parameter_range_are_refused_at_load(tmp_path, old, new, field):
    """Deliver item 2. Before: loaded, refused only at the first doStep without being named."""
    scene = _scene(tmp_path, "quadrotor", old, new)
    with pytest.raises(ModelInputError, match=re.escape(f"field '{field}': |value| must be <= 1e+100")):
        load_scene(scene)


@pytest.mark.parametrize(
    "kind, name, value, fragment",
    [
        ("dual_spin", "J_wheel", 5e-324, "J_wheel must be in [1e-100, 1e+100] kg.m2"),  # item 7
        ("gravity_gradient_boom", "orbit_angle", 1e17, "|orbit_angle| must be <= 1e+06 rad"),  # item 6
        ("gravity_gradient_boom", "orbit_angle", -1e300, "|orbit_angle| must be <= 1e+06 rad"),
        ("eccentric_orbit", "x_cm[1]", 0.0, "the body is at the central body"),  # item 8
        ("eccentric_orbit", "x_cm[1]", 1e-100, "the body is at the central body"),
    ],
)
def test_start_values_out_of_range_are_refused_at_initialisation(kind, name, value, fragment):
    """Items 6, 7, 8 through FMI start values (the path of rbfmu run --set and the sweeps).
    Before: orbit_angle 1e17 ran with the angle frozen and status OK; J 5e-324 failed at the
    first doStep as "non-finite (an overflow)"; x_cm = 0 said the parameters overflow."""
    refused_at_exit_initialization(kind, name, value, fragment)


def test_orbit_angle_within_its_range_still_advances():
    """The range's reason: at |angle| = 1e6 rad one doStep of n H still moves the angle by
    n H to round-off (a double there resolves 1.2e-10 rad)."""
    lib = shared_library("gravity_gradient_boom")
    inst = lib.instantiate()
    vr = lib.info.vr
    assert inst.set_float64([vr["orbit_angle"]], [1e6]) == OK
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    n = inst.get_float64([vr["n_orbit"]])[1][0]
    H = 10.0
    assert inst.do_step(0.0, H)[0] == OK
    angle = inst.get_float64([vr["orbit_angle"]])[1][0]
    assert abs((angle - 1e6) - n * H) <= 2 * 1.2e-10, (angle - 1e6, n * H)
    inst.free()
