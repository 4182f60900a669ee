"""The top on a moving pivot (feature moving_pivot): the FMU against the top in g - a, the shaker and Newton's law.

docs/theory.md §7.3: about a pivot B accelerating at a_B, Euler's equations gain
M r_C × a_B, so a constant a_B is the heavy top in gravity g − a_B (rbcheck.closed_forms.free_flight).
Tolerances come from the methods' phase error C (h|ω|/2)^p per radian turned
(docs/robustness.md §1), at h = 1e-4 s, |ω| = 150 rad/s.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fmu.drive.instance import FmuInstance
from fmu.drive.run import run_fmu
from modelsrc.methods import METHODS
from modelsrc.scene import load_scene
from rbcheck.checks.balances import balances, held_run
from rbcheck.checks.motion import pivot_force_newton
from rbcheck.closed_forms.free_flight import (
    accelerating_pivot_top,
    harmonic_motion,
    held_pivot_motion,
    shaker_position_bound,
)
from rbcheck.numerics.rotation_np import quat_to_matrix, rotation_angle_between

from ..harness.stepping import fixed_steps

EPS = np.finfo(float).eps
T = 0.5  # s: 75 rad turned at 150 rad/s, 2.9 nutation periods
# (C, p) of the phase error per radian turned (docs/robustness.md §1); exact_free with
# gravity's kicks is order 2 with the splitting's constant 1/12
PHASE = {"rk4": (1 / 120, 4), "gauss6": (1 / 100800, 6), "exact_free": (1 / 12, 2)}


def _zero_start():
    return {f"{b}[{j}]": 0.0 for b in ("x_pivot", "v_pivot") for j in (1, 2, 3)}


@pytest.mark.parametrize("a", [(0.0, 0.0, 3.0), (2.0, -1.0, 4.0)])
@pytest.mark.parametrize("method", list(PHASE))
def test_constant_pivot_acceleration_is_gravity_g_minus_a(fmus, a, method):
    sc = load_scene("top_on_shaker")
    sc_a = dataclasses.replace(sc, inputs={"a_pivot": np.array(a)})
    r = run_fmu(
        fmus["top_on_shaker"], sc_a, stop_time=T, start_values=_zero_start() | fixed_steps(sc.fixed_step, method)
    )
    w, q = accelerating_pivot_top(sc.inertia, sc.mass, sc.r_cm, sc.g, a, sc.q0, sc.w0, r.time)
    dw = float(np.max(np.abs(r.vector("w_body") - w)))
    da = float(np.max(rotation_angle_between(quat_to_matrix(r.vector("q")), quat_to_matrix(q))))
    C, p = PHASE[method]
    W = 150.0
    h = min(sc.fixed_step, METHODS[method].rotation_limit / W)
    tol = 10 * C * (h * W / 2) ** p * W * T + 1e-12  # relative, 10x margin (+ the closed form's round-off)
    print(f"\n{method} a = {a}: |dw| {dw:.1e} rad/s, attitude {da:.1e} rad (tol {tol:.1e} relative)")
    assert dw < tol * W and da < tol
    # the pivot itself: x = ½ a t² exactly (a polynomial every method integrates exactly)
    assert np.max(np.abs(r.vector("x_pivot") - 0.5 * np.outer(r.time**2, a))) < 1e3 * EPS


def test_pivot_force_of_a_resting_top_is_newtons_law(fmus):
    """Upright and not spinning, the pivot accelerating at a: f_pivot = M (a_C − g)."""
    sc = load_scene("top_on_shaker")
    a = np.array([1.0, -2.0, 3.0])
    start = (
        _zero_start() | {f"w_body[{j}]": 0.0 for j in (1, 2, 3)} | {"q[1]": 1.0, "q[2]": 0.0, "q[3]": 0.0, "q[4]": 0.0}
    )
    with FmuInstance(fmus["top_on_shaker"]) as inst:
        inst.set(start | {f"a_pivot[{j + 1}]": a[j] for j in range(3)})
        inst.initialize(0.0, 1.0)
        f = inst.get([f"f_pivot[{j}]" for j in (1, 2, 3)])
    # upright: r_C = l e_z; ω = 0 but ω̇ = I⁻¹ r × M (g − a) ≠ 0 for a horizontal a, so
    # a_C = a + ω̇ × r: the horizontal part of f differs from M a by M (ω̇ × r)
    I_B = sc.inertia + sc.mass * (sc.r_cm @ sc.r_cm * np.eye(3) - np.outer(sc.r_cm, sc.r_cm))
    wdot = np.linalg.solve(I_B, np.cross(sc.r_cm, sc.mass * (sc.g - a)))
    expected = sc.mass * (a + np.cross(wdot, sc.r_cm) - sc.g)
    assert np.allclose(f, expected, rtol=1e-14, atol=1e-14)
    assert f[2] == pytest.approx(sc.mass * (a[2] + 9.81), rel=1e-15)  # vertical: M (a_z + g)


def test_shaker_pivot_follows_its_held_motion(fmus):
    sc = load_scene("top_on_shaker")
    r = run_fmu(fmus["top_on_shaker"], sc, inputs="hold")  # as an importer without intermediate update
    spec = sc.inputs["a_pivot"]
    acc = np.array([sc.input_mean("a_pivot", t0, t1) for t0, t1 in zip(r.time[:-1], r.time[1:])])
    x_h, v_h = held_pivot_motion(r.time, acc, sc.x0, sc.v0)
    scale = 5e-4 + float(np.max(np.abs(v_h))) * sc.stop_time
    n = round(sc.stop_time / sc.fixed_step)  # at least the internal steps the error control takes
    assert np.max(np.abs(r.vector("x_pivot") - x_h)) < n * EPS * scale
    # held at its mean over each step, the pivot velocity is exact at every communication point
    x_c, v_c = harmonic_motion(spec.amplitude, spec.omega, spec.phase, sc.x0, sc.v0, r.time)
    assert np.max(np.abs(r.vector("v_pivot") - v_c)) < n * EPS * float(np.max(np.abs(v_c)))
    dx = float(np.max(np.abs(r.vector("x_pivot") - x_c)))
    bound = shaker_position_bound(float(np.max(np.abs(spec.amplitude))), spec.omega, sc.step)
    print(f"\nshaker: max |x_pivot + A cos wt| = {dx:.3e} m, bound H^2 A w^2/6 (+10 %) = {bound:.3e} m")
    assert dx < bound and dx > 0.5 * bound  # the bound is tight: the O(H²) error is real


def test_pivot_force_is_newtons_law_for_exudyns_centre_of_mass(fmus):
    # f_pivot (FMU) vs M (Δv_cm/H − g) from Exudyn's spherical joint to a prescribed shaker:
    # within 3x Exudyn's own Richardson estimate (its trapezoidal rule is order 2)
    sc = load_scene("top_on_shaker")
    diff, est, scale = pivot_force_newton(fmus["top_on_shaker"], sc, 0.05)
    print(f"\nf_pivot vs Exudyn's M dv/dt: {diff:.2e} N (Exudyn estimate {est:.1e} N) of |f| {scale:.3g} N")
    assert diff <= 3 * est + 1e-12 * scale and scale > 4.0


def test_work_of_the_shaker_is_the_change_of_energy(fmus):
    # E_total(t) − E_total(0) = ∫ f_pivot · v_pivot dt (docs/theory.md §7.3). Simpson per
    # step errs by H⁵|P⁗|/2880 with |P⁗| ≤ |P| ν⁴ (ν = 150 rad/s, |P| ≤ 0.6 W): 2000 steps
    # give ≤ 2e-7 J; the run keeps it far below (measured 1e-11 J)
    sc = load_scene("top_on_shaker")
    b = balances(sc, held_run(fmus["top_on_shaker"], sc, sc.stop_time))
    bound = 2000 * (1e-3) ** 5 / 2880 * 0.6 * 150.0**4
    print(f"\nshaker work balance {b.work:.1e} J (bound {bound:.1e} J), work done {b.work_done:.2e} J")
    assert b.work < bound
