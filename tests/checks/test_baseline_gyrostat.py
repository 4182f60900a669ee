"""The scipy baseline of the gyrostat (rbcheck.baselines.gyrostat) against theory §8's closed forms and the FMU."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import simpson

from fmu.drive.run import run_fmu
from modelsrc.scene import load_scene
from rbcheck.baselines.gyrostat import integrate_gyrostat
from rbcheck.baselines.motion import integrate
from rbcheck.closed_forms import dual_spin as ds


def test_the_linearised_nutation_of_the_dual_spin_closed_form():
    # docs/theory.md §8.3 with s = z, (t1, t2) = (x, y): started with ω_x = ε only, the
    # linearised spin gives ω_x = ε cos νt, ω_y = ε k1/(I_y ν) sin νt. With ε = 1e-6 rad/s the
    # neglected terms are quadratic: ω_s and ν shift by O(ε²) = 1e-12, a phase of 4e-11 after
    # 40 s; DOP853's rtol 1e-13 is per component, so ω_x, ω_y carry ~1e-13 of themselves per
    # step (a few hundred steps). Measured 3.6e-13 of ε; asserted 1e-8. A wrong k (h_w with the
    # other sign, or the wheel left out: the bare body is unstable) is off by O(1).
    eps = 1e-6
    sc = dataclasses.replace(load_scene("dual_spin"), w0=np.array([eps, 0.0, 1.0]))
    I = np.diag(sc.inertia)
    h_w = sc.rotors["wheel"].J * sc.rotors["wheel"].Omega0
    nu = ds.nutation_frequency(I, 2, 1.0, h_w)
    k1, _ = ds.stability_factors(I, 2, 1.0, h_w)
    grid = np.linspace(0.0, 40.0, 81)
    tr = integrate(sc, grid)  # dispatches to the gyrostat baseline
    assert tr.extra["rotors"] == ["wheel"]
    wx, wy = tr.w_body[:, 0] / eps, tr.w_body[:, 1] / eps
    assert np.max(np.abs(wx - np.cos(nu * grid))) < 1e-8
    assert np.max(np.abs(wy - k1 / (I[1] * nu) * np.sin(nu * grid))) < 1e-8
    # the wheel's absolute rate ω_z + Ω is constant with u = 0 (J Ω̇ = u − J g·ω̇, §8.1)
    absolute = tr.w_body[:, 2] + tr.extra["Omega"][:, 0]
    assert np.max(np.abs(absolute - absolute[0])) < 1e-11 * absolute[0]


@pytest.mark.parametrize("u", [0.0, 2.0])
def test_momentum_and_energy_balances_of_the_baseline(u):
    # §8.1: the world momentum R (I ω + h) is conserved whatever u (the motor torques are
    # internal); §8.2: E(T) − E(0) = ∫ u Ω dt (Simpson on the 0.05 s grid: error
    # ~ T H⁴ max|(uΩ)''''|/180 < 1e-10 of the work). DOP853 at rtol 1e-13 over 200 restarts:
    # drifts of a few 1e-13; asserted 1e-11 (momentum) and 1e-9 (energy).
    sc = load_scene("dual_spin")
    grid = np.linspace(0.0, 10.0, 201)
    tr = integrate_gyrostat(sc, grid, rotor_u={"wheel": u})
    inv = tr.extra["invariants"]
    L = inv["L_world"]
    assert np.max(np.linalg.norm(L - L[0], axis=1)) < 1e-11 * np.linalg.norm(L[0])
    E, Om = inv["E_kin"], tr.extra["Omega"][:, 0]
    work = simpson(u * Om, x=grid)
    assert abs(E[-1] - E[0] - work) < 1e-9 * max(abs(work), E[0])
    if u:
        assert Om[-1] - Om[0] > 15.0  # u/J = 2 rad/s² for 10 s, less the body's reaction


@pytest.mark.parametrize("u", [0.0, 2.0])
def test_the_baseline_matches_the_fmu(fmus, u):
    # The FMU at its defaults (rk8, tolerance 1e-10 per second: errors add up to ~1e-10 T
    # relative, docs/theory.md §5.5) against the baseline at rtol 1e-13 over T = 10 s: asserted
    # within 1e-10 T of the scale of each state (ω: |ω0|, Ω: max|Ω|, q: 1).
    sc = load_scene("dual_spin")
    T, H = 10.0, 0.05
    grid = np.linspace(0.0, T, round(T / H) + 1)
    tr = integrate_gyrostat(sc, grid, rotor_u={"wheel": u})
    r = run_fmu(fmus["dual_spin"], sc, stop_time=T, step=H, input_fn=lambda t, y: {"u_wheel": u})
    assert np.allclose(r.time, grid, rtol=0, atol=1e-12)
    tol = 1e-10 * T
    dw = np.max(np.abs(r.vector("w_body") - tr.w_body)) / np.linalg.norm(sc.w0)
    dq = np.max(np.abs(r.vector("q") - tr.q))
    Om = tr.extra["Omega"][:, 0]
    dOm = np.max(np.abs(r.values["Omega_wheel"] - Om)) / np.max(np.abs(Om))
    print(f"u = {u}: |Δω| {dw:.1e}, |Δq| {dq:.1e}, |ΔΩ| {dOm:.1e} (relative)")
    assert dw < tol and dq < tol and dOm < tol
    assert math.isclose(r.values["E_kin"][-1], tr.extra["invariants"]["E_kin"][-1], rel_tol=tol)


def test_the_baseline_refuses_what_it_does_not_cover():
    sc = load_scene("dual_spin")
    with pytest.raises(ValueError, match="rotor_u names pump: not torque-mode rotors of dual_spin"):
        integrate_gyrostat(sc, np.array([0.0, 1.0]), rotor_u={"pump": 1.0})
    moving = dataclasses.replace(sc, features=sc.features | {"moving_pivot"})
    with pytest.raises(ValueError, match=r"a moving pivot with rotors is not in rbcheck's numpy equations"):
        integrate(moving, np.array([0.0, 1.0]))
    with pytest.raises(ValueError, match="inputs must be 'continuous' or 'hold', got 'mean'"):
        integrate(sc, np.array([0.0, 1.0]), inputs="mean")


def test_a_harmonic_motor_torque_acts_inside_the_intervals():
    # u = 2 cos(3 t) N·m from the scene's schedule, "continuous": evaluated at every
    # right-hand-side call, so E(T) − E(0) = ∫ u Ω dt (§8.2) with u at the fine times (the
    # integral by Simpson on 2001 points: error ~1e-12 of the work); held at its value at
    # the start of each 0.5 s interval of the coarse run instead (the 1 ms run barely
    # notices), the coarse run's energy would miss the work by O(1).
    from modelsrc.scene_inputs import Harmonic

    u = Harmonic(amplitude=np.array([2.0]), omega=3.0, offset=np.array([0.0]))
    sc = dataclasses.replace(load_scene("dual_spin"), inputs={"u_wheel": u})
    assert sc.inputs_varying_in_step == ["u_wheel"]
    grid = np.linspace(0.0, 2.0, 5)
    tr = integrate(sc, grid)
    fine = np.linspace(0.0, 2.0, 2001)
    tr_fine = integrate(sc, fine)
    work = simpson(2.0 * np.cos(3.0 * fine) * tr_fine.extra["Omega"][:, 0], x=fine)
    E = tr.extra["invariants"]["E_kin"]
    assert abs(E[-1] - E[0] - work) < 1e-9 * abs(work) and abs(work) > 10.0


def test_speed_mode_propellers_on_a_free_body_match_the_fmu(fmus):
    """quadrotor: four speed-mode propellers (Ω and Ω̇ read from the harmonic schedules at
    every right-hand-side call), thrust at the rotor points, drag, gravity, translation
    (docs/theory.md §8.5, §8.6), against the FMU fed the same schedules continuously.
    Measured over the scene's 6 s: q 1.2e-15, ω 2.1e-15 rad/s, x_cm 1.4e-14 m, L_world
    4.9e-17 N m s, E_total 1.6e-13 J; DOP853 at rtol 1e-13 is ~1e-13 accurate, so 1e-11."""
    sc = load_scene("quadrotor")
    r = run_fmu(fmus["quadrotor"], sc)
    tr = integrate(sc, r.time)
    inv = tr.extra["invariants"]
    assert np.max(np.abs(tr.q - r.vector("q"))) < 1e-11
    assert np.max(np.abs(tr.w_body - r.vector("w_body"))) < 1e-11
    assert np.max(np.abs(tr.extra["x_cm"] - r.vector("x_cm"))) < 1e-11
    assert np.max(np.abs(inv["L_world"] - r.vector("L_world"))) < 1e-11
    assert np.max(np.abs(inv["E_total"] - r.values["E_total"])) < 1e-11 * np.max(np.abs(r.values["E_total"]))
    # held inputs (the means of Ω and Ω̇ over each interval) are another system (x_cm 2.4e-5 m off): the mean of
    # the thrust k_f Ω² is not k_f (mean Ω)², so the height drifts off (the yaw, linear in
    # the differential δ, does not)
    held = integrate(sc, r.time, inputs="hold")
    assert np.max(np.abs(held.extra["x_cm"] - tr.extra["x_cm"])) > 1e-6
