"""The speed-command rotor mode (mode_command.py, docs/theory.md §8.8) through its FMU: closed form, balances, Exudyn.

One user scene, built once: a body with principal moments (4, 5, 6) kg·m², a wheel along
body z and a second rotor on an oblique axis, both in command mode (Ω̇ = (Ω_cmd − Ω)/τ_m).
With the second rotor at rest and its command 0 it stays at rest exactly, so the scene is
the closed form's (rbcheck.closed_forms.motor_lag): a step command from rest about a
principal axis of a free body. Started spinning and driven by commands that jump at the
communication points, it checks that the motors' torques are internal (world angular
momentum conserved); the jointed Exudyn gyrostat (rbcheck.exudyn.rotors) checks the body's
answer to the lagging rotor.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fmu.build.build_fmu import build_fmu
from fmu.drive.instance import FmuError
from modelsrc.errors import ModelInputError
from modelsrc.model import build_model
from modelsrc.scene import load_scene
from rbcheck.checks.common import method_codes, run
from rbcheck.checks.richardson import richardson_agreement
from rbcheck.closed_forms.motor_lag import rk4_error_bound, spin_up_from_rest
from rbcheck.exudyn.rotors import covers, simulate_gyrostat

from ..harness.scenes import write_scene

SCENE = """
name = "command_rotors"
outputs = ["q", "w_body", "L_world", "E_kin"]
[body]
principal_moments = [4.0, 5.0, 6.0]
[rotors.wheel]
axis = [0.0, 0.0, 1.0]
J = 0.5
mode = "command"
tau_m = 0.05
[rotors.tilt]
axis = [0.6, 0.0, 0.8]
J = 0.2
mode = "command"
tau_m = 0.02
[initial]
w_body = [0.0, 0.0, 0.0]
[inputs]
Omega_cmd_wheel = 100.0
[experiment]
stop_time = 0.3
step = 0.01
methods = ["rk4", "rk8"]
"""
I_Z, J, TAU, CMD = 6.0, 0.5, 0.05, 100.0


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    d = tmp_path_factory.mktemp("command_rotors")
    sc = load_scene(write_scene(d, SCENE))
    return sc, build_fmu(sc, d)


def test_the_variables_of_a_command_rotor():
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        sc = load_scene(write_scene(Path(d), SCENE))
    m = build_model(sc)
    v = {x.name: (x.kind.name, x.unit, x.start) for x in m.variables}
    assert v["Omega_cmd_wheel"] == ("INPUT", "rad/s", 100.0) and v["Omega_cmd_tilt"] == ("INPUT", "rad/s", 0.0)
    assert v["Omega_wheel"] == ("STATE", "rad/s", 0.0) and v["tau_m_wheel"][1:] == ("s", 0.05)
    assert v["u_wheel"][:2] == ("OUTPUT", "N.m")
    assert sc.input_names == ["Omega_cmd_wheel", "Omega_cmd_tilt"] and not sc.conserves_energy


def test_a_step_command_from_rest_follows_the_closed_form_at_rk4s_order(built):
    """Fixed-step RK4 at h = 1e-3 and 5e-4 s against Ω = Ω_cmd (1 − e^(−t/τ)), ω_z = −J Ω/I_z,
    u = J (1 − J/I_z) Ω̇. The bound is RK4's leading error term (motor_lag.rk4_error_bound,
    4.9e-8 rad/s at h = 1e-3 s; the next term is h/τ = 2 % of it): measured 5.0e-8 and 3.1e-9,
    ratio 16.1. I_z ω + J Ω is linear in the state, so RK4 keeps it to round-off and ω's error
    is exactly J/I_z times Ω's."""
    sc, fmu = built
    codes = method_codes(fmu)
    errors = []
    for h in (1e-3, 5e-4):
        r = run(fmu, sc, start_values={"method": codes["rk4"], "tolerance": 0.0, "h_max": h})
        exact = spin_up_from_rest(r.time, CMD, TAU, J, I_Z)
        w = r.vector("w_body")
        Om = r.values["Omega_wheel"]
        bound = 1.1 * rk4_error_bound(h, CMD, TAU)
        err = float(np.max(np.abs(Om - exact["Omega"])))
        assert 0.5 * bound < err <= bound, (h, err, bound)  # it is RK4's error, not a smaller or larger one
        assert np.max(np.abs(w[:, 2] - exact["w"])) <= J / I_Z * bound
        assert np.max(np.abs(w[:, 2] + J * Om / I_Z)) <= 1e-14  # the momentum about z, to round-off
        assert np.max(np.abs(r.values["u_wheel"] - exact["u"])) <= J * (1 - J / I_Z) / TAU * bound + 1e-12
        assert not np.any(w[:, :2]) and not np.any(r.values["Omega_tilt"])  # the motion stays about z
        errors.append(err)
    assert 15.0 < errors[0] / errors[1] < 17.0, errors  # 2^4: fourth order


def test_total_angular_momentum_is_conserved_with_motor_torques_only(built):
    """The body spinning about no principal axis, the oblique rotor spinning at the start, and
    both commands jumping at every communication point (a zero-order hold of a controller):
    the motors' torques are internal, so L_world stays; E_kin does not (the motors work).
    The error control (rk8, tolerance 1e-10 per second, 0.3 s) keeps L to ~1e-11 of |L|;
    measured 3e-15 relative."""
    sc, fmu = built

    def commands(t, outputs):
        k = round(t / sc.step)
        return {"Omega_cmd_wheel": 80.0 * np.sin(0.7 * k), "Omega_cmd_tilt": -60.0 + 15.0 * (k % 4)}

    r = run(fmu, sc, start_values={"w_body[1]": 0.3, "w_body[2]": -0.2, "w_body[3]": 0.5, "Omega_tilt": 20.0},
            input_fn=commands)  # fmt: skip
    L = r.vector("L_world")
    drift = float(np.max(np.linalg.norm(L - L[0], axis=1)) / np.linalg.norm(L[0]))
    assert drift <= 1e-11, drift
    E = r.values["E_kin"]
    assert np.ptp(E) > 0.1 * E[0]  # the motors did work: the test is not of a body left alone
    assert np.ptp(r.values["Omega_tilt"]) > 50.0


@pytest.mark.slow
def test_exudyn_gyrostat_converges_to_the_fmu_at_second_order(built):
    """The wheel's step command on a body spinning off its axes, in Exudyn (the wheel on a
    joint, its rate relative to the hub prescribed by the lag's solution), h = 1e-3 and
    5e-4 s against the FMU (rk8, error-controlled, 1e-12 here): the trapezoidal rule's ratio 4
    on halving h, the Richardson remainder well below the finer run's error."""
    sc, fmu = built
    w0 = np.array([0.05, -0.03, 0.4])
    r = run(fmu, sc, start_values={"w_body[1]": w0[0], "w_body[2]": w0[1], "w_body[3]": w0[2]})
    ref = {"q": r.vector("q"), "w_body": r.vector("w_body"), "u_wheel": r.values["u_wheel"]}
    # the oblique rotor at rest under a zero command is inert: its inertia stays in the hub's
    ex = dataclasses.replace(sc, w0=w0, rotors={"wheel": sc.rotors["wheel"]})
    assert covers(ex) is None and covers(sc) is not None
    coarse, fine = (simulate_gyrostat(ex, h=h) for h in (1e-3, 5e-4))
    ag = richardson_agreement(ref, coarse, fine, list(ref))
    for key in ref:
        ratio = float(np.max(np.abs(coarse[key] - ref[key]))) / ag.plain[key]
        assert 3.5 < ratio < 4.6, (key, ratio)
        assert ag.diff[key] < ag.plain[key] / 8, (key, ag.diff[key], ag.plain[key])
    assert np.max(np.abs(fine["Omega_wheel"] - r.values["Omega_wheel"])) < 1e-9


@pytest.mark.parametrize(
    "old, new, field, match",
    [
        ("tau_m = 0.05\n", "", "rotors.wheel.tau_m", "required in mode 'command'"),
        ('J = 0.5\nmode = "command"\n', "J = 0.5\n", "rotors.wheel.tau_m", "is not a key of mode 'torque'"),
        ("tau_m = 0.05", "tau_m = 0.0", "rotors.wheel.tau_m", r"must be in \[1e-100, 1e\+100\].*got 0.0"),
        ("tau_m = 0.05", 'tau_m = "fast"', "rotors.wheel.tau_m", "must be a number"),
        ("tau_m = 0.05", "tau_m = 1e-9", "rotors.wheel.tau_m", r"must be >= 1e-06 s .*got 1e-09"),
        ("[rotors.tilt]", "[rotors.cmd_tilt]", "rotors.cmd_tilt", "nor starting with abs_ or dot_ or cmd_"),
        ("[initial]", "[initial]\nOmega_cmd_wheel = 3.0", "initial", "Omega_cmd_wheel"),
    ],
)
def test_bad_command_rotors_are_refused_in_one_line(tmp_path, old, new, field, match):
    with pytest.raises(ModelInputError, match=f"field '{field}.*{match}") as exc:
        build_model(load_scene(write_scene(tmp_path, SCENE.replace(old, new))))
    assert "\n" not in str(exc.value)


def test_a_motor_time_constant_set_through_the_fmu_is_checked(built):
    sc, fmu = built
    with pytest.raises(FmuError, match="tau_m_wheel must be >= 1e-06 s"):
        run(fmu, sc, stop_time=0.02, start_values={"tau_m_wheel": 1e-9})
