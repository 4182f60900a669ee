"""`rbfmu check --scene FILE` applies the checks of every feature the scene uses, each row with a verdict.

Issue 34.1: a user's orbit satellite got "not applicable" on every row and exit 0; a wheel
scene got no independent reference. Now rbcheck.checks.feature_table maps every feature
unit to its checks; the rows carry tolerances (rbcheck.checks.feature_checks: ten times the
FMU's tolerance x T, three times a reference's own error estimate); a scene with no
applicable check, a check that could not run or a row out of its tolerance fails the command.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fmu.build.build_fmu import build_fmu
from modelsrc.registry import FEATURE_UNITS
from modelsrc.scene import load_scene
from rbcheck.checks import cli, feature_checks, generic, orbit_features, registry
from rbcheck.checks.feature_table import FEATURE_CHECKS, check_outputs, unknown_generic_titles

from ..harness.scenes import write_scene

ORBIT = """
name = "user_orbit_sat"
outputs = ["q", "w_body", "E_kin"]
[features]
orbit = true
gravity_gradient = true
[orbit]
rate = 0.0011067  # rad/s: 2 pi / 5677 s
[body]
principal_moments = [120.0, 100.0, 60.0]
[initial]
q = [0.9999995, 0.0, 0.001, 0.0]
w_body = [0.0, -0.0011067, 0.0]
[experiment]
stop_time = 5677.0
step = 10.0
methods = ["rk8"]
"""

# a momentum-bias satellite: one free wheel along the orbit normal (body -y)
BIAS = (
    ORBIT.replace("user_orbit_sat", "user_bias_sat")
    .replace("[initial]", "[rotors.wheel]\naxis = [0.0, -1.0, 0.0]\nJ = 0.05\n[initial]\nOmega_wheel = 400.0")
    .replace('"E_kin"]', '"E_kin", "L_world"]')
)

PYRAMID = """
name = "user_pyramid"
outputs = ["q", "w_body", "w_world", "E_kin", "L_world"]
[body]
principal_moments = [50.0, 60.0, 40.0]
[rotors.w1]
axis = [0.5773502691896258, 0.5773502691896258, 0.5773502691896258]
J = 0.02
[rotors.w2]
axis = [-0.5773502691896258, 0.5773502691896258, 0.5773502691896258]
J = 0.02
[rotors.w3]
axis = [-0.5773502691896258, -0.5773502691896258, 0.5773502691896258]
J = 0.02
[rotors.w4]
axis = [0.5773502691896258, -0.5773502691896258, 0.5773502691896258]
J = 0.02
[inputs]
u_w1 = [[0.0, 0.01], [0.5, -0.01], [1.0, 0.0]]
u_w3 = 0.002
[initial]
w_body = [0.01, -0.02, 0.015]
Omega_w1 = 100.0
Omega_w2 = -50.0
Omega_w3 = 20.0
[experiment]
stop_time = 1.0
step = 0.05
methods = ["rk8"]
"""

CENTRAL = """
name = "user_central_sat"
outputs = ["q", "w_body", "E_kin", "E_total", "x_cm", "v_cm"]
[features]
translation = true
central_gravity = true
[central_gravity]
mu = 3.986004418e14
[body]
principal_moments = [30.0, 50.0, 70.0]
mass = 50.0
[initial]
x_cm = [6800000.0, 0.0, 0.0]
v_cm = [0.0, 7900.0, 500.0]
w_body = [0.001, 0.002, 0.0005]
[experiment]
stop_time = 1000.0
step = 10.0
methods = ["rk8"]
"""

# a prescribed rate and nothing else: only the closed-form trajectory (the uniform rotation)
# applies; with it made not applicable below, no generic check and no feature check does
NOTHING = """
name = "user_spinner"
[features]
prescribed_rate = true
[body]
principal_moments = [1.0, 2.0, 3.0]
[initial]
w_body = [0.0, 0.0, 1.0]
[experiment]
stop_time = 1.0
step = 0.1
methods = ["rk4"]
"""


def _build(tmp_path_factory, text: str, name: str):
    d = tmp_path_factory.mktemp(name)
    path = write_scene(d, text, name)
    sc = load_scene(path)
    sc = dataclasses.replace(sc, outputs=tuple(sc.outputs) + check_outputs(sc))  # as `rbfmu check` builds it
    return sc, build_fmu(sc, d)


@pytest.fixture(scope="module")
def orbit_sat(tmp_path_factory):
    return _build(tmp_path_factory, ORBIT, "user_orbit_sat")


@pytest.fixture(scope="module")
def bias_sat(tmp_path_factory):
    return _build(tmp_path_factory, BIAS, "user_bias_sat")


def _rows(rep: registry.SceneReport) -> dict[str, registry.Row]:
    return {r.quantity: r for r in rep.rows}


def test_every_feature_unit_has_an_entry_in_the_table():
    """A new feature unit without an entry in rbcheck.checks.feature_table fails here."""
    assert [f.unit for f in FEATURE_CHECKS] == [u.name for u in FEATURE_UNITS]
    assert unknown_generic_titles() == []


def test_a_row_verdict():
    assert registry.Row("x", "-", 1e-9, float("nan"), 0.0, 1e-8).passed
    assert not registry.Row("x", "-", 1e-7, float("nan"), 0.0, 1e-8).passed
    assert not registry.Row("x", "-", float("nan"), float("nan"), 0.0, 1e-8).passed  # nan never passes
    assert not registry.Row("x", "-", 1.0, float("nan")).judged


@pytest.mark.slow
def test_orbit_satellite_gets_jacobi_exudyn_pitch_and_scipy_rows_that_pass(orbit_sat):
    """On main every row was "not applicable" and the command exited 0. Measured: E_jacobi
    drift 2e-16, |q - q_Exudyn| 6e-14, pitch 1.484792e-3 rad/s against 1.484794e-3 (allowed
    2 A^2 + 1e-7 relative: the amplitude's second-order shift)."""
    sc, fmu = orbit_sat
    rep = registry.scene_report(sc, fmu)
    assert rep.failures() == [], registry.format_report(rep)
    judged = [r for r in rep.rows if r.judged]
    assert len(judged) >= 6
    rows = _rows(rep)
    assert rows["orbit: max|E_jacobi - E_jacobi(0)| / (n^2 tr I + max E_kin)"].fmu < 1e-13
    pitch = rows["orbit: pitch libration frequency (I_y - J, J = 0)"]
    assert abs(pitch.fmu / pitch.closed - 1) < 1e-5
    assert any(q.startswith("orbit: max|q - q_Exudyn|") for q in rows)


@pytest.mark.slow
def test_orbit_satellite_fails_against_a_wrong_reference(orbit_sat, monkeypatch):
    """The scipy reference of a body whose I_y is 0.1 % off: its row fails, and so does the scene."""
    sc, fmu = orbit_sat
    wrong = dataclasses.replace(sc, inertia=np.diag([120.0, 100.1, 60.0]))
    real = feature_checks.integrate
    monkeypatch.setattr(feature_checks, "integrate", lambda s, t, rtol: real(wrong, t, rtol=rtol))
    out = feature_checks.scipy_reference_check(fmu, sc, False)
    assert not all(r.passed for r in out.rows)


@pytest.mark.slow
def test_momentum_bias_satellite_pitch_needs_the_free_wheel(bias_sat, monkeypatch):
    """The pitch frequency with a free wheel along the orbit normal is n sqrt(3 (I_x - I_z)/(I_y - J)):
    the row passes with J and fails without it (the J term, 2.5e-4 relative, is 30x the tolerance)."""
    sc, fmu = bias_sat
    rep = registry.scene_report(sc, fmu)
    assert rep.failures() == [], registry.format_report(rep)
    assert "orbit: pitch libration closed form" not in rep.not_applicable
    monkeypatch.setattr(orbit_features, "free_wheel_J", lambda s: 0.0)
    (row,) = orbit_features.pitch_libration_check(fmu, sc, False).rows
    assert not row.passed


@pytest.mark.slow
def test_wheel_pyramid_gets_momentum_work_exudyn_and_scipy_rows(tmp_path_factory, monkeypatch):
    """Four wheels in a pyramid with motor torques: L_world conserved, the work balance with the
    motor power, the jointed Exudyn gyrostat (1 s, Richardson from h = 1e-3, 5e-4 s) and scipy;
    Exudyn's rotors 1 % heavier than the scene's make the Exudyn rows fail."""
    sc, fmu = _build(tmp_path_factory, PYRAMID, "user_pyramid")
    rep = registry.scene_report(sc, fmu)
    assert rep.failures() == [], registry.format_report(rep)
    titles = {r.quantity.split(":")[0] for r in rep.rows}
    assert "rotors" in titles
    assert "rotors: Exudyn jointed gyrostat" not in rep.not_applicable
    real = feature_checks.simulate_gyrostat
    heavier = dataclasses.replace(sc, rotors={n: dataclasses.replace(r, J=1.01 * r.J) for n, r in sc.rotors.items()})
    monkeypatch.setattr(feature_checks, "simulate_gyrostat", lambda s, **kw: real(heavier, **kw))
    out = feature_checks.rotor_exudyn_check(fmu, sc, False)
    assert not all(r.passed for r in out.rows)


@pytest.mark.slow
def test_central_field_gets_invariants_and_runge_lenz(tmp_path_factory):
    sc, fmu = _build(tmp_path_factory, CENTRAL, "user_central_sat")
    rep = registry.scene_report(sc, fmu)
    assert rep.failures() == [], registry.format_report(rep)
    rows = _rows(rep)
    assert rows["central field: max|e_RL - e_RL,scipy| (Runge-Lenz vector)"].passed


@pytest.mark.slow
def test_no_applicable_check_and_a_check_that_cannot_run_exit_non_zero(tmp_path, capsys, monkeypatch, orbit_sat):
    """A scene for which no check applies: exit 1 with the reason, not "done" and 0."""
    path = write_scene(tmp_path, NOTHING, "user_spinner")
    assert cli.main(["--scene", str(path), "--fmu-dir", str(tmp_path)]) == 0  # closed form, bearing torque judged
    assert "user_spinner: passed: 6 row(s) within their tolerances" in capsys.readouterr().out

    def no_closed_form(*a, **kw):
        raise registry.NotApplicable("no closed form (made so by the test)")

    monkeypatch.setattr(generic, "closed_form_trajectory", no_closed_form)
    assert cli.main(["--scene", str(path), "--fmu-dir", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "No check applies to this scene" in out
    assert "cross-check FAILED for 1 of 1 scene(s)" in out
    sc, fmu = orbit_sat

    def broken(*a, **kw):
        raise RuntimeError("the reference diverged")

    monkeypatch.setattr(orbit_features, "simulate_orbit", broken)
    rep = registry.scene_report(sc, fmu, quick=True)
    assert "orbit: Exudyn orbit model" in rep.errors
    assert any("could not run" in f and "diverged" in f for f in rep.failures())
