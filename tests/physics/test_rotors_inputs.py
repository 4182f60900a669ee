"""Rotor motor torques scheduled in the scene file (issue 28): constants, tables, harmonics, --set.

docs/theory.md §8.1: a rotor's axial equation is J (g·ω̇ + Ω̇) = u, so its absolute axial
momentum h = J (g·ω + Ω) (the output h_<name>) changes by exactly ∫ u dt, whatever the body
does, and the total world angular momentum stays constant (the motor torque is internal).
Both hold to round-off, so the schedule the driver gives the FMU is measured through them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fmu.build.build_fmu import build_fmu
from fmu.drive.inputs import node_input_names
from fmu.drive.run import run_fmu
from modelsrc.model import build_model
from modelsrc.scene import load_scene
from rbcheck.checks import gyrostat as gy

from ..harness.scenes import write_scene

# Two wheels on the dual-spin body: a with a table, b with a harmonic (N·m, s); and s in
# speed mode (docs/theory.md §8.5), its rate Ω_s = 20 cos(2 t + 0.3) rad/s prescribed.
FIXED = {"tolerance": 0.0, "h_max": 1e-3}  # rk8 at fixed 1 ms steps: truncation below round-off
SCHEDULED = """
name = "gyro_sched"
outputs = ["q", "w_body", "E_kin", "L_world"]
[body]
principal_moments = [350.0, 200.0, 300.0]
[rotors.a]
axis = [0.0, 0.0, 1.0]
J = 1.0
[rotors.b]
axis = [0.6, 0.8, 0.0]
J = 0.5
[rotors.s]
axis = [0.0, 0.6, 0.8]
J = 0.3
mode = "speed"
[initial]
w_body = [0.01, 0.0, 1.0]
Omega_a = 100.0
[inputs]
u_a = [[0.0, 2.0], [1.0, 0.0], [1.5, -1.0]]
u_b = { amplitude = 0.8, omega = 3.0, phase = 0.4 }
Omega_s = { amplitude = 20.0, omega = 2.0, phase = 0.3 }
[experiment]
methods = ["rk8"]
stop_time = 3.0
step = 0.05
"""
T = 3.0
W, PH, A = 3.0, 0.4, 0.8


def _impulse_a(t: float) -> float:
    """∫₀ᵗ u_a dt of the table (N·m·s)."""
    return 2.0 * min(t, 1.0) - max(0.0, t - 1.5)


def _impulse_b(t: float) -> float:
    """∫₀ᵗ 0.8 cos(3 t + 0.4) dt (N·m·s)."""
    return A / W * (math.sin(W * t + PH) - math.sin(PH))


@pytest.fixture(scope="module")
def sched(tmp_path_factory):
    d = tmp_path_factory.mktemp("sched")
    sc = load_scene(write_scene(d, SCHEDULED, "gyro_sched"))
    return sc, build_fmu(sc, d)


def test_scalar_schedules_are_read_and_their_start_values_written():
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        sc = load_scene(write_scene(Path(d), SCHEDULED, "gyro_sched"))
    assert sc.input_names == ["u_a", "u_b", "Omega_s", "Omega_dot_s"]
    assert sc.input_at("u_a", 1.2).tolist() == [0.0] and sc.input_at("u_a", 2.0).tolist() == [-1.0]
    assert sc.switch_times() == [0.0, 1.0, 1.5]
    assert node_input_names(sc) == ["u_b", "Omega_s", "Omega_dot_s"]  # the harmonics, asked at internal nodes
    assert sc.input_at("Omega_dot_s", 0.7)[0] == pytest.approx(-40.0 * math.sin(1.7), rel=1e-14)
    starts = {v.name: v.start for v in build_model(sc).variables}
    assert starts["u_a"] == 2.0 and starts["u_b"] == pytest.approx(A * math.cos(PH), rel=1e-15)


def test_the_scheduled_motor_torques_change_each_wheel_momentum_by_their_impulse(sched):
    """h_a(t) − h_a(0) = ∫ u_a and h_b(t) − h_b(0) = ∫ u_b (closed forms above) at every
    communication point, and L_world constant. rk8 at fixed 1 ms steps (FIXED): truncation
    error ~(ω h)⁸ far below round-off, so the balances hold to round-off of h ~ 100 N·m·s;
    asserted 1e-9 absolute (N·m·s), L_world 1e-13 relative. Measured in the print."""
    sc, fmu = sched
    r = run_fmu(fmu, sc, start_values=FIXED)
    t = r.time
    assert 1.0 in t and 1.5 in t  # the table's switching times are communication points
    ha, hb = r.values["h_a"], r.values["h_b"]
    err_a = np.max(np.abs(ha - ha[0] - np.array([_impulse_a(x) for x in t])))
    err_b = np.max(np.abs(hb - hb[0] - np.array([_impulse_b(x) for x in t])))
    L = r.vector("L_world")
    dL = float(np.max(np.linalg.norm(L - L[0], axis=1)) / np.linalg.norm(L[0]))
    print(f"h_a err {err_a:.2e}, h_b err {err_b:.2e} N m s, L_world rel drift {dL:.2e}")
    assert abs(_impulse_a(T) - 0.5) < 1e-15 and abs(ha[-1] - ha[0]) > 0.4  # the schedule acted
    assert err_a < 1e-9 and err_b < 1e-9
    assert dL < 1e-13


def test_set_replaces_the_schedule_of_a_motor_torque(sched):
    """`--set u_a=0.25` (a start value for the input): u_a constant over the run, u_b keeps
    its harmonic (docs/user_guide.md §2: a value for an input replaces its schedule)."""
    sc, fmu = sched
    r = run_fmu(fmu, sc, start_values={"u_a": 0.25})
    ha, hb = r.values["h_a"], r.values["h_b"]
    assert ha[-1] - ha[0] == pytest.approx(0.25 * T, abs=1e-9)
    assert hb[-1] - hb[0] == pytest.approx(_impulse_b(T), abs=1e-9)


def test_held_inputs_give_the_same_impulses(sched):
    """inputs="hold" (an importer without intermediate update): the harmonic held at its
    mean over each step has the same integral per step, so the wheel momenta at the
    communication points are the same closed forms."""
    sc, fmu = sched
    r = run_fmu(fmu, sc, inputs="hold")
    hb = r.values["h_b"]
    assert hb[-1] - hb[0] == pytest.approx(_impulse_b(T), abs=1e-9)


def test_the_energy_balance_needs_the_motor_power_u_times_the_relative_rate(fmus):
    """dual_spin with the motor-torque table of rbcheck.checks.gyrostat (2, 0, −3, 1 N·m over
    10 s) as its scene schedule: E(t) − E(0) = ∫ u Ω_rel dt (docs/theory.md §8.2) per step by
    Simpson, error H⁵|P⁗|/2880 per step ~ 1e-9 J of ~1e3 J of work; asserted 1e-7 J. Without
    the motor power (the generic balance before issue 28's rotors) the residual is the whole
    work. L_world (wheel included) constant: round-off, asserted 1e-11 N·m·s of |L| ~ 300."""
    b = gy.motor_balance(fmus["dual_spin"], load_scene("dual_spin"))
    print(b)
    assert abs(b.work_done) > 100.0
    assert b.work < 1e-7
    assert b.work_without_motor > 0.5 * abs(b.work_done)
    assert b.angular_momentum < 1e-11


def test_the_closed_loop_slew_matches_the_exact_sampled_data_recursion(fmus):
    """reaction_wheel_slew with the PD law of rbcheck.closed_forms.slew closed from fmpy (u from q and
    w_body at every communication point, held over the step). From rest, I ω + h = 0, so the
    body turns about the eigenaxis n with ω̇ constant over each step: the recursion of
    rbcheck.closed_forms.slew.eigenaxis_reference is exact, and the FMU (rk8, 1e-10 1/s) meets it to its
    round-off: measured 6.7e-16 rad, asserted 1e-12 rad. L_world and the wheels-vs-body
    exchange: round-off of |h| ~ 2 N·m·s (measured 1e-15), asserted 1e-13. The final error
    1.79e-7 rad is the sampled-data PD loop's own (its decay over 40 s), not the FMU's."""
    from rbcheck.checks.wheels import slew

    s = slew(fmus["reaction_wheel_slew"], load_scene("reaction_wheel_slew"))
    print(s)
    assert s.phi0 == pytest.approx(math.pi / 2, rel=1e-15)
    assert s.body_momentum_max > 1.0 and s.wheel_rate_max > 50.0  # the wheels did take the momentum
    assert s.L_max < 1e-13 and s.exchange < 1e-13
    assert s.dphi < 1e-12 and s.dw < 1e-12
    assert s.final_error == pytest.approx(s.final_error_ref, abs=1e-12)
    assert s.final_error < 1e-6


def test_a_speed_mode_rotor_follows_its_rate_and_outputs_the_torque_it_needs(sched):
    """Rotor s in speed mode (docs/theory.md §8.5): Omega_abs_s − g·ω is the prescribed
    Ω_s(t) (to round-off), the world angular momentum stays constant although Ω_s swings by
    ±20 rad/s (the body takes the reaction; fixed 1 ms rk8 steps, round-off), and the output
    u_s is the motor torque that does it: h_s(T) − h_s(0) = ∫ u_s dt (Simpson over the 10 ms
    communication points: error T H⁴ max|u⁗|/180 ~ 4e-8 N·m·s; asserted 1e-6)."""
    from scipy.integrate import simpson

    sc, fmu = sched
    r = run_fmu(fmu, sc, step=0.01, start_values={**FIXED, "u_a": 0.25})  # no table jumps in ω̇
    g = np.array([0.0, 0.6, 0.8])
    Om = r.values["Omega_abs_s"] - r.vector("w_body") @ g
    assert np.max(np.abs(Om - 20.0 * np.cos(2.0 * r.time + 0.3))) < 1e-12
    L = r.vector("L_world")
    dL = float(np.max(np.linalg.norm(L - L[0], axis=1)) / np.linalg.norm(L[0]))
    hs, us = r.values["h_s"], r.values["u_s"]
    err = abs(hs[-1] - hs[0] - simpson(us, x=r.time))
    print(f"speed mode: L_world rel drift {dL:.2e}, |dh_s - int u_s| {err:.2e} N m s, max|u_s| {np.abs(us).max():.3g}")
    assert dL < 1e-13
    assert err < 1e-6 and np.max(np.abs(us)) > 1.0


def test_the_quadrotor_hovers_yaws_by_the_rotor_reaction_and_keeps_its_momentum_balances(fmus):
    """quadrotor (docs/theory.md §8.6), rk8 at its defaults. Hover (speeds held at ±Ω_h with
    4 k_f Ω_h² = m g): at rest to round-off (measured |v| 4e-15 m/s). Differential speeds
    ±Ω_h + 40 sin 2t: the exact planar yaw I_zz ω_z = 4 J (δ(0) − δ) − 8 k_m Ω_h ∫δ, the
    climb ∫ 4 k_f δ² dt / m and L_z = ∫ drag, all closed forms met to round-off (measured
    9e-15 rad/s, 6e-15 m/s, 2e-16 N·m·s; asserted 1e-12). Tilted by rotor 1 +5, rotor 3
    −5 rad/s: the world balances of angular and linear momentum with the thrust turning with
    the body, Simpson per 2 ms step (error H⁴ |ω|⁴ ~ 3e-11 relative of ~12 N·s; measured
    1e-16 N·m·s, 1.2e-10 N·s; asserted 1e-12, 1e-8)."""
    from rbcheck.checks.propellers import quadrotor_run

    q = quadrotor_run(fmus["quadrotor"], load_scene("quadrotor"))
    print(q)
    assert q.hover_x < 1e-12 and q.hover_v < 1e-12 and q.hover_w < 1e-12
    assert q.yaw_peak > 1.0 and q.yaw_err < 1e-12 and q.tilt_rate < 1e-12
    assert q.L_err < 1e-12 and q.vz_err < 1e-12
    assert q.tilt_w > 1.0 and q.tilt_L < 1e-12 and q.tilt_p < 1e-8


def test_motors_and_propellers_mark_what_the_scene_no_longer_conserves():
    """fmu.drive.summary and the drift checks read Scene.conserves_energy / torque_free: motor
    schedules and speed-mode rotors do work (§8.2, §8.5), propellers exert moments (§8.6)."""
    assert load_scene("dual_spin").conserves_energy  # u = 0: E conserved
    quad = load_scene("quadrotor")
    assert not quad.conserves_energy and not quad.torque_free
    slew = load_scene("reaction_wheel_slew")
    assert slew.torque_free and slew.conserves_energy  # no schedule: u from the importer's loop
    assert not slew.with_inputs_held({"u_x": 0.1}).conserves_energy
