"""Extreme bodies and stiffness: thin rods, near-spheres, flat plates, sleeping top, stiff friction, big torques.

The cases, tolerances and their derivation: see tests/harness/extreme_harness.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from modelsrc.errors import ModelInputError
from modelsrc.methods import METHODS as METHOD_TABLE
from modelsrc.scene import load_scene
from rbcheck.closed_forms import free_asymmetric, free_symmetric
from rbcheck.closed_forms.heavy_top import HeavyTop, TopParams, init_from_state, sleeping_threshold

from ..harness.extreme_harness import (
    EPS,
    EXPLICIT,
    LONG,
    METHODS,
    PHASE,
    STATE_NAMES,
    attitude_error,
    min_substeps,
    norm_L,
    omega0,
    principal,
    rel_drift,
    report,
    simulate,
)
from ..harness.fmi3_ctypes import OK
from ..harness.scenes import write_scene

# ---------------------------------------------------------------------------------------
# Thin rod, stiff inertia ratios; near-sphere; flat plate
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "I",
    [(1e-6, 1.0, 1.0 + 1e-6), (1e-9, 1.0, 1.0 + 1e-9), (1e-3, 1.0, 1.0 + 1e-3)],
    ids=["rod1e-6", "rod1e-9", "rod1e-3"],
)
@pytest.mark.parametrize("method", METHODS)
def test_thin_rod(free, method, I):
    """Nearly a rod (I1 << I2 ~ I3, the triangle inequality nearly tight) tumbling with w0 =
    (1, 0.5, 1) for 1 s, default steps: vs rbcheck.closed_forms.free_asymmetric (which agrees with a
    DOP853 solution at rtol 1e-13 to 1e-13 here). Every method is stable and keeps E and
    |L|; all but the splitting are accurate. The splitting's w error grows like h^2/I1
    (its axis flows exchange L1 with the others; divided by I1 it becomes w1): reported."""
    w0 = np.array([1.0, 0.5, 1.0])
    run = simulate(free, method, {**principal(I), **omega0(w0)}, 1e-2, 100)
    assert run.status == OK and np.all(np.isfinite(run.vec(*STATE_NAMES)))
    w_ref, q_ref = free_asymmetric.solve(np.array(I), w0, np.array([1.0, 0, 0, 0]), run.time)
    werr, att = float(np.max(np.abs(run.w - w_ref))), float(np.max(attitude_error(run, q_ref)))
    dE, dL = rel_drift(run.out["E_kin"]), rel_drift(norm_L(run))
    # |L| and E: 1000 internal steps, round-off N eps ~ 2e-13 (splitting's E: O(h^2) ~ 1e-8)
    assert dL <= 1e-12
    assert dE <= (1e-7 if method == "splitting" else 1e-12)
    if method != "splitting":
        # h w ~ 1.5e-3: order-2 midpoint ~ T w (h w)^2/12 ~ 3e-7; higher orders ~ round-off; the
        # reference and the conditioning of w1 = L1/I1 add ~1e-9 at I1 = 1e-9 (measured)
        assert werr <= 1e-6 and att <= 1e-6
    report(f"thin rod I1={I[0]:g}", method, w_err=werr, att_err=att, dE=dE, dL=dL)


@pytest.mark.parametrize("method", METHODS)
def test_near_sphere_keeps_E_and_L_to_round_off(free, method):
    """I = (1, 1+1e-12, 1+2e-12): w nearly constant; 1000 doSteps of 10 substeps (N = 1e4):
    |L| and E constant to round-off, bounded by N eps (one rounding per step, worst case
    linear accumulation); |q| = 1 to 4 eps. w drift is reported (physically < 1e-11)."""
    w0 = np.array([0.3, 1.0, -0.7])
    run = simulate(free, method, {**principal((1.0, 1.0 + 1e-12, 1.0 + 2e-12)), **omega0(w0)}, 1e-2, 1000)
    N = sum(run.substeps)
    dE, dL = rel_drift(run.out["E_kin"]), rel_drift(norm_L(run))
    assert dE <= N * EPS and dL <= N * EPS, (dE, dL, N * EPS)
    assert np.max(np.abs(np.linalg.norm(run.q, axis=1) - 1)) <= 4 * EPS
    report(
        "near sphere",
        method,
        N=N,
        dE_per_Neps=dE / (N * EPS),
        dL_per_Neps=dL / (N * EPS),
        w_drift=float(np.max(np.abs(run.w - w0))),
    )


@pytest.mark.parametrize("I", [(0.25, 0.75, 1.0), (1.0, 1.0, 2.0)], ids=["plate", "square_plate"])
@pytest.mark.parametrize("method", METHODS)
def test_flat_plate_at_triangle_equality_runs(free, method, I):
    """I3 = I1 + I2 exactly (a flat plate) is valid and runs: vs the closed forms, 10 s."""
    w0 = np.array([0.3, 1.0, -0.7])
    run = simulate(free, method, {**principal(I), **omega0(w0)}, 1e-2, 1000)
    assert run.status == OK
    if I[0] == I[1]:
        w_ref, q_ref = free_symmetric.solve(I[0], I[2], w0, [1, 0, 0, 0], run.time)
    else:
        w_ref, q_ref = free_asymmetric.solve(np.array(I), w0, np.array([1.0, 0, 0, 0]), run.time)
    werr, att = float(np.max(np.abs(run.w - w_ref))), float(np.max(attitude_error(run, q_ref)))
    # h w ~ 1.3e-3, T = 10 s: midpoint/splitting (order 2) ~ T w (h w)^2 ~ 2e-5; others ~ round-off
    assert werr <= (1e-4 if method in ("implicit_midpoint", "splitting") else 1e-10)
    report(f"flat plate I={I}", method, w_err=werr, att_err=att)


def test_just_past_the_triangle_equality_is_rejected(tmp_path, free):
    """I3 = I1 + I2 + 1e-10 violates the triangle inequality beyond its tolerance
    (1e-12 tr I, docs/theory.md §3.4): refused at scene load and at FMU initialisation;
    + 1e-13 is within the tolerance and accepted by both."""
    for delta, ok in ((1e-13, True), (1e-10, False), (3e-9, False)):
        text = f"[body]\nprincipal_moments = [1.0, 2.0, {3.0 + delta!r}]\n[initial]\nw_body = [1.0, 0.0, 0.0]\n"
        path = write_scene(tmp_path, text, f"plate_{'ok' if ok else 'bad'}_{int(-math.log10(delta))}")
        if ok:
            load_scene(path)
        else:
            with pytest.raises(ModelInputError, match=r"I_i \+ I_j >= I_k") as exc:
                load_scene(path)
            assert str(path) in str(exc.value) and "body.principal_moments" in str(exc.value)
        inst = free.fmi.instantiate()
        assert inst.set_float64([free.fmi.info.vr["I_principal[3]"]], [3.0 + delta]) == OK
        assert inst.enter_initialization_mode(0.0) == OK
        status = inst.exit_initialization_mode()
        errors = "\n".join(inst.errors_since(0))
        inst.free()
        assert (status == OK) == ok, errors
        if not ok:
            assert "I_i + I_j >= I_k" in errors and f"I_principal[3]={3.0 + delta:.17g}" in errors


# ---------------------------------------------------------------------------------------
# Sleeping top: exactly vertical, and at (1 +- 1e-3) x the threshold
# ---------------------------------------------------------------------------------------


def _top_params() -> tuple[TopParams, float]:
    sc = load_scene("sleeping_top")
    m, l = sc.mass, float(sc.r_cm[2])
    I1 = sc.inertia[0, 0] + m * l**2  # about the pivot (parallel axes, docs/theory.md §3.2)
    p = TopParams(I1, sc.inertia[2, 2], m, -float(sc.g[2]), l)
    return p, sleeping_threshold(p.I1, p.I3, p.M, p.g, p.l)


@pytest.mark.parametrize("factor", [1 - 1e-3, 1 + 1e-3])
@pytest.mark.parametrize("method", METHODS)
def test_sleeping_top_exactly_vertical(top, method, factor):
    """theta = 0 exactly (q = 1): gravity's torque is exactly zero, the quaternion state has
    no singularity there, so the top stays vertical (even below the threshold: an
    unstable equilibrium kept exactly) and the z-x-z outputs stay finite (the layer sets
    psi = 0 at the gimbal lock, docs/theory.md §1.3). 1 s, 1e4 internal steps."""
    _, wc = _top_params()
    run = simulate(
        top,
        method,
        {"c_friction": 0.0, "q[1]": 1.0, "q[2]": 0.0, "q[3]": 0.0, "q[4]": 0.0, **omega0((0, 0, factor * wc))},
        1e-2,
        100,
    )
    assert run.status == OK
    eul = run.vec("euler_zxz[1]", "euler_zxz[2]", "euler_zxz[3]")
    assert np.all(np.isfinite(eul))
    # theta stays 0 up to the Newton residual of the Gauss methods (relative 1e-14 of |Z|)
    assert np.max(run.out["euler_zxz[2]"]) <= 1e-12
    # the spin angle phi + psi advances as w3 t: the attitude is right, not just finite; error (*)
    # with h = 1e-4 (the scene's h_max), or round-off N eps w3 T for rk8/splitting (exact flow)
    angle = np.unwrap(eul[:, 0] + eul[:, 2])
    w3, T, N = factor * wc, run.time[-1], sum(run.substeps)
    p, c = PHASE.get(method, (8, 0.0))
    bound = w3 * T * c * (1e-4 * w3 / 2) ** p + 10 * N * EPS * w3 * T
    assert np.max(np.abs(angle - angle[0] - w3 * run.time)) <= bound
    report(f"sleeping top theta=0 w3={factor:g}x", method, theta_max=float(np.max(run.out["euler_zxz[2]"])))


@pytest.mark.parametrize("factor", [1 - 1e-3, 1 + 1e-3])
@pytest.mark.parametrize("method", METHODS)
def test_sleeping_top_near_threshold(top, method, factor):
    """Tilt 1 mrad, w3 = (1 -+ 1e-3) x threshold, no friction: the nutation amplitude of
    the closed form (rbcheck.closed_forms.heavy_top) is 92x (below) and 22x (above) the start tilt, and
    the FMU follows theta(t) over half a nutation period. Tolerance relative to the
    amplitude: near the threshold the amplitude amplifies the per-step error ~1/(2e-3);
    with h w3 = 1.2e-2: order 2 -> 500 (h w3)^2 = 7e-2, order >= 4 -> 1e-4 (>> 500 (h w3)^4)."""
    params, wc = _top_params()
    from modelsrc.quaternion import quat_from_euler_zxz

    q0 = quat_from_euler_zxz(0.0, 1e-3, 0.0)
    w0 = np.array([0.0, 0.0, factor * wc])
    ref = HeavyTop(params, init_from_state(q0, w0))
    T = 0.5 * ref.period + 0.05
    run = simulate(
        top, method, {"c_friction": 0.0, **{f"q[{k + 1}]": q0[k] for k in range(4)}, **omega0(w0)}, 1e-2, int(T / 1e-2)
    )
    assert run.status == OK
    theta_ref = ref.angles(run.time)[0]
    amp = float(np.arccos(ref.u1))
    err = float(np.max(np.abs(run.out["euler_zxz[2]"] - theta_ref))) / amp
    order2 = method in ("implicit_midpoint", "splitting")
    assert err <= (7e-2 if order2 else 1e-4), err
    dE = float(np.max(np.abs(run.out["E_total"] - run.out["E_total"][0])) / abs(run.out["E_kin"][0]))
    report(
        f"sleeping top tilt 1e-3 w3={factor:g}x",
        method,
        ref_amplitude=amp,
        fmu_amplitude=float(np.max(run.out["euler_zxz[2]"])),
        rel_err=err,
        dE_rel=dE,
    )


# ---------------------------------------------------------------------------------------
# Stiff friction
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", METHODS)
def test_stiff_friction(free, method):
    """c/I1 = 1e6 1/s (c = 1e6 N m s, I = (1, 2, 3)), communication step 1e-2: explicit
    methods sub-step to h c/I <= limit on their own, implicit ones are stable at h = 1e-3
    (h c/I = 1e3); the energy never increases from one communication point to the next
    (friction only removes energy). The exact E(1e-2) is ~E0 e^-6667 = 0: the Gauss
    methods are A- but not L-stable (|R(-1e3)| ~ 1), so they leave most of E: reported."""
    run = simulate(free, method, {"c_friction": 1e6, **omega0((1.0, 2.0, -3.0))}, 1e-2, 20)
    assert run.status == OK, run.log
    E = run.out["E_kin"]
    assert np.all(np.isfinite(E)) and np.all(np.diff(E) <= 0), E
    if method in EXPLICIT:  # rk4/rk8 sub-step to their stability limit; the splitting's friction flow is exact
        assert min(run.substeps) >= min_substeps(method, 1e-2, 1e6, 1e-3, spin=float(np.sqrt(14.0)))
        assert E[1] <= 1e-12 * E[0]  # resolved: gone after one communication step
    report(
        "stiff friction c/I=1e6",
        method,
        substeps=run.substeps[0],
        E1_over_E0=float(E[1] / E[0]),
        E20_over_E0=float(E[-1] / E[0]),
        wall_ms=run.wall * 1e3,
    )


@pytest.mark.parametrize("method", METHODS)
def test_stiffer_friction_explicit_refuse_implicit_run(free, method):
    """c/I1 = 1e11: RK4 and RK8 would need 1e9 substeps per 1e-2 s, 4e9 and 1.2e10 evaluations
    against the work limit 5e7, and must refuse with a message saying what to do; the implicit
    methods step (and E decreases), and so
    does the splitting, whose friction flow e^{-c h/I} is exact at any step."""
    run = simulate(free, method, {"c_friction": 1e11, **omega0((1.0, 2.0, -3.0))}, 1e-2, 3)
    if method in ("rk4", "rk8"):
        assert run.status != OK and len(run.substeps) == 0
        text = "\n".join(run.log)
        assert "more than work_limit = 5e+07" in text and "choose an implicit method" in text, text
    else:
        assert run.status == OK and np.all(np.diff(run.out["E_kin"]) <= 0)
    report("stiff friction c/I=1e11", method, refused=run.status != OK)


# ---------------------------------------------------------------------------------------
# Long horizon: 1e7 internal steps
# ---------------------------------------------------------------------------------------

LONG_STEPS = {
    "rk4": 10_000,
    "rk8": 10_000,
    "splitting": 10_000,
    "exact_free": 1_000,
    "implicit_midpoint": 1_000,
    "gauss4": 300,
    "gauss6": 100,
}


@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
def test_long_horizon(free, method):
    """Tennis racket (I = (1, 2, 3), w0 = (0.01, 1, 0.01)), h_max 1e-5, doSteps of 1e-2
    (1000 substeps each): 1e4 doSteps = 1e7 internal steps for the explicit methods (and
    for all with RBFMU_LONG_HORIZON=1). Drift of |q| - 1, E and |L|: round-off only (the
    truncation error at h w = 1e-5 is < 1e-20 per step for order >= 2 ... except the
    splitting's bounded O(h^2) energy error, ~1e-10) -> bound N eps, the worst case."""
    n = 10_000 if LONG else LONG_STEPS[method]
    run = simulate(
        free,
        method,
        {"h_max": 1e-5, **omega0((0.01, 1.0, 0.01))},
        1e-2,
        n,
        names=STATE_NAMES + ("E_kin", "L_world[1]", "L_world[2]", "L_world[3]"),
    )
    assert run.status == OK and set(run.substeps) == {1000}
    N = sum(run.substeps)
    dq = float(np.max(np.abs(np.linalg.norm(run.q, axis=1) - 1)))
    dE, dL = rel_drift(run.out["E_kin"]), rel_drift(norm_L(run))
    assert dq <= 4 * EPS
    assert dL <= N * EPS
    assert dE <= (N * EPS + 1e-9 if method == "splitting" else N * EPS)
    report(
        "long horizon",
        method,
        internal_steps=N,
        dq=dq,
        dE=dE,
        dL=dL,
        dE_per_sqrtN_eps=dE / (math.sqrt(N) * EPS),
        wall_s=run.wall,
    )


# ---------------------------------------------------------------------------------------
# Torque steps of 1e6 N m, torques switching sign every step (closed loop)
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("h_max", [1e-3, 1e-6])
@pytest.mark.parametrize("method", METHODS)
def test_torque_step_1e6(free, method, h_max):
    """From rest, tau = 1e6 N m about principal axis 3 (I3 = 3): exactly w3 = tau t/I3,
    attitude angle tau t^2/(2 I3). w is linear in t, which every method integrates
    exactly: error = round-off, N eps w. The body spins up to 3.3e4 rad/s within 0.1 s:
    explicit methods re-step when the end-of-step rate exceeds their limit. Attitude
    error reported; with h_max 1e-6 (h w <= 0.033) it must be small: (*) with W = w_max."""
    tau, I3, H, n = 1e6, 3.0, 1e-2, 10
    run = simulate(free, method, {"h_max": h_max, **omega0((0, 0, 0)), "tau_body[3]": tau}, H, n)
    assert run.status == OK, run.log
    t = run.time
    N = sum(run.substeps)
    w_exact = tau * t / I3
    assert np.max(np.abs(run.out["w_body[3]"] - w_exact)) <= N * EPS * w_exact[-1] + 1e-12
    assert np.max(np.abs(run.w[:, :2])) <= 1e-12 * w_exact[-1]
    angle = tau * t**2 / (2 * I3)
    att = float(np.max(attitude_error(run, np.column_stack([np.cos(angle / 2), 0 * t, 0 * t, np.sin(angle / 2)]))))
    # re-stepped as the body spins up: the final steps within twice the rotation limit
    assert H / run.substeps[-1] * w_exact[-1] <= 2 * METHOD_TABLE[method].rotation_limit
    if h_max == 1e-6:
        W = w_exact[-1]
        p, c = PHASE.get(method, (8, 0.0))
        # (*) at the final (largest) rate, plus round-off of the angle: N eps angle
        bound = (W * t[-1] * c * (h_max * W / 2) ** p if c else 0.0) + N * EPS * angle[-1]
        assert att <= bound, (att, bound)
    report(
        f"torque step 1e6 h_max={h_max:g}",
        method,
        substeps_first_last=f"{run.substeps[0]}/{run.substeps[-1]}",
        w_err_rel=float(np.max(np.abs(run.out["w_body[3]"] - w_exact)) / w_exact[-1]),
        att_err=att,
        angle=float(angle[-1]),
    )


@pytest.mark.parametrize("method", METHODS)
def test_torque_switching_sign_every_step(free, method):
    """Closed loop: tau3 = +1e6 N m while w3 < tau H/(2 I3), else -1e6, so it flips every
    step; exact response at the communication points: w3 alternates 0, tau H/I3 (3333
    rad/s), and the attitude angle grows by tau H^2/(2 I3) per step. h_max 1e-5 (h w <=
    0.033)."""
    tau, I3, H, n = 1e6, 3.0, 1e-2, 20

    def bang_bang(t, out):
        return {"tau_body[3]": -tau if out["w_body[3]"] > tau * H / (2 * I3) else tau}

    run = simulate(free, method, {"h_max": 1e-5, **omega0((0, 0, 0))}, H, n, input_fn=bang_bang)
    assert run.status == OK
    k = np.arange(len(run.time))
    w_exact = np.where(k % 2 == 1, tau * H / I3, 0.0)
    N = sum(run.substeps)
    werr = float(np.max(np.abs(run.out["w_body[3]"] - w_exact)))
    assert werr <= N * EPS * tau * H / I3
    angle = k * tau * H**2 / (2 * I3)
    att = float(np.max(attitude_error(run, np.column_stack([np.cos(angle / 2), 0 * k, 0 * k, np.sin(angle / 2)]))))
    W = tau * H / I3
    p, c = PHASE.get(method, (8, 0.0))
    assert att <= (W * H * n * c * (1e-5 * W / 2) ** p if c else 0.0) + N * EPS * angle[-1]
    report("bang-bang 1e6 N m", method, w_err_rel=werr / W, att_err=att, angle=float(angle[-1]))
