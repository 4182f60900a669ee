"""Extreme cases, fast spin: every method sub-steps to its rotation limit; its phase error is as its order predicts.

The cases, tolerances and their derivation: see tests/harness/extreme_harness.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from modelsrc.methods import METHODS as METHOD_TABLE
from rbcheck.closed_forms import free_asymmetric, free_symmetric

from ..harness.extreme_harness import (
    EPS,
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

# ---------------------------------------------------------------------------------------
# Fast spin about a principal axis: exact solution w = const, q turning uniformly
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("W", [1e4, 1e5])
@pytest.mark.parametrize("method", METHODS)
def test_fast_spin_default_h_max(free, method, W):
    """|w| = W about axis 3, communication step 1e-2 s, h_max 1e-3 s (h_max W = 10 and
    100 rad): explicit methods must sub-step to their stability limit on their own, all
    methods keep w exact (it is an equilibrium of Euler's equations), |q| = 1 and E, |L|
    constant; the attitude error is measured (it is O(1) rad for every method but the
    splitting, whose free flow is exact here: h_max sets accuracy, the guard only stability)."""
    H, n, h_max = 1e-2, 10, 1e-3
    run = simulate(free, method, {"h_max": h_max, **omega0((0, 0, W))}, H, n)
    assert run.status == OK, run.log
    need = min_substeps(method, H, W, h_max)
    assert min(run.substeps) >= need, (run.substeps, need)
    # w stays (0, 0, W): the Euler right-hand side is exactly zero there; Newton's dense
    # solve may leave round-off (measured <= 1e-18 W), bound 1e-13 W
    assert np.max(np.abs(run.w - [0, 0, W])) <= 1e-13 * W
    assert np.max(np.abs(np.linalg.norm(run.q, axis=1) - 1)) <= 4 * EPS  # projected every step
    t = run.time
    q_exact = np.column_stack([np.cos(W * t / 2), 0 * t, 0 * t, np.sin(W * t / 2)])
    err = attitude_error(run, q_exact)
    if method == "splitting":  # exact flow: round-off of the rotation angle W t, N eps W T
        assert err[-1] <= 10 * EPS * W * t[-1]
    report(
        f"fast spin W={W:g}",
        method,
        substeps=run.substeps[0],
        h_W=H / run.substeps[0] * W,
        att_err=float(err[-1]),
        wall_ms=run.wall * 1e3,
    )


@pytest.mark.parametrize("method", METHODS)
def test_fast_spin_phase_error_matches_theory(free, method):
    """W = 1e4 rad/s with h_max chosen for accuracy (h W / 2 = 0.05, or 0.02 where the
    method's rotation limit is smaller, so the FMU takes exactly that step): the attitude
    error after T = 0.1 s equals (*) within 5 % (the next term is O((hW/2)^2) <= 0.25 %
    relative); rk8 and the splittings are exact up to round-off here (rk8's error ~
    (0.05)^9 W T; a pure principal spin is an exact axis flow)."""
    W, T = 1e4, 0.1
    x = 0.05 if METHOD_TABLE[method].rotation_limit >= 0.1 else 0.02
    h = 2 * x / W
    run = simulate(free, method, {"h_max": h, **omega0((0, 0, W))}, 1e-2, round(T / 1e-2))
    t = run.time
    err = attitude_error(run, np.column_stack([np.cos(W * t / 2), 0 * t, 0 * t, np.sin(W * t / 2)]))[-1]
    if method in PHASE:
        p, c = PHASE[method]
        predicted = W * T * c * x**p
        assert abs(err / predicted - 1) < 0.05, (err, predicted)
    else:
        predicted = 0.0
        assert err <= 10 * EPS * W * T  # round-off of the angle W T over N steps
    report(f"phase error W=1e4, hW/2={x}", method, att_err=float(err), predicted=predicted)


# ---------------------------------------------------------------------------------------
# Fast spin with a small off-axis component: closed forms rbcheck.closed_forms.free_symmetric/_asymmetric
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("I", [(1.0, 2.0, 3.0), (2.0, 2.0, 3.0)], ids=["asymmetric", "symmetric"])
@pytest.mark.parametrize("method", METHODS)
def test_fast_off_axis_spin_accurate_step(free, method, I):
    """w0 = (1e-3 W, 0, W), W = 1e4, h W/2 = 0.05: errors against the closed forms. The
    attitude error is the principal-axis phase error (*) up to the small transverse
    motion (bound: 2x (*)). The transverse w (amplitude A = 1e-3 W) turns at
    nu = W sqrt((I3-I1)(I3-I2)/(I1 I2)) (W for diag(1,2,3), W/2 for diag(2,2,3)); its phase
    error after T is nu T C (h nu)^p, so |dw| <= 2 A nu T C (h nu)^p (factor 2: measured
    0.9 and 0.45 of the estimate). rk8 is at round-off; the splitting (order 2, constant
    unknown) is only reported."""
    W, T, x = 1e4, 0.1, 0.05
    h = 2 * x / W
    w0 = np.array([1e-3 * W, 0.0, W])
    run = simulate(free, method, {"h_max": h, **principal(I), **omega0(w0)}, 1e-2, round(T / 1e-2))
    assert run.status == OK
    t = run.time
    if I[0] == I[1]:
        w_ref, q_ref = free_symmetric.solve(I[0], I[2], w0, [1, 0, 0, 0], t)
    else:
        w_ref, q_ref = free_asymmetric.solve(np.array(I), w0, np.array([1.0, 0, 0, 0]), t)
    att = float(np.max(attitude_error(run, q_ref)))
    werr = float(np.max(np.abs(run.w - w_ref)))
    N = sum(run.substeps)
    floor_w, floor_att = N * EPS * W, N * EPS * W * T  # round-off of w and of the angle W T
    if method in PHASE:
        p, c = PHASE[method]
        nu = W * math.sqrt((I[2] - I[0]) * (I[2] - I[1]) / (I[0] * I[1]))
        assert att <= 2 * W * T * c * x**p + floor_att, att
        assert werr <= 2 * 1e-3 * W * nu * T * c * (h * nu) ** p + floor_w, werr
    elif method == "rk8":  # order 8: (0.1)^8 W T ~ 1e-5 times its small constant; measured 7e-12
        assert att <= 1e-9 and werr <= 1e-9 * W
    report(f"off-axis W=1e4 I={I}", method, att_err=att, w_err_rel=werr / W)


@pytest.mark.parametrize("W", [1e4, 1e5])
@pytest.mark.parametrize("method", METHODS)
def test_fast_off_axis_spin_default_h_max_stays_bounded(free, method, W):
    """Default h_max = 1e-3 s: bounded, finite, |q| = 1, |L| and E to the method's level
    (Gauss: exact quadratic invariants; splitting: exact |L|); errors vs the closed form
    recorded. Explicit methods at their stability limit."""
    I = (1.0, 2.0, 3.0)
    w0 = np.array([1e-3 * W, 0.0, W])
    run = simulate(free, method, {**principal(I), **omega0(w0)}, 1e-2, 10)
    assert run.status == OK and np.all(np.isfinite(run.vec(*STATE_NAMES)))
    assert min(run.substeps) >= min_substeps(method, 1e-2, W, 1e-3)
    assert np.max(np.abs(np.linalg.norm(run.q, axis=1) - 1)) <= 4 * EPS
    dE, dL = rel_drift(run.out["E_kin"]), rel_drift(norm_L(run))
    if method in ("implicit_midpoint", "gauss4", "gauss6"):
        assert dE <= 1e-13 and dL <= 1e-13  # quadratic invariants, Newton tolerance 1e-14
    elif method == "splitting":  # exact rotations: |L| to round-off, at worst N eps over N substeps
        assert dL <= max(1e-13, sum(run.substeps) * EPS)
    else:  # rk4/rk8: the transverse motion holds ~(1e-3)^2 of E and L: even losing it all
        assert dE <= 1e-5 and dL <= 1e-5  # (numerical damping at h*rate ~ 1) stays below 1e-5
    w_ref, q_ref = free_asymmetric.solve(np.array(I), w0, np.array([1.0, 0, 0, 0]), run.time)
    report(
        f"off-axis W={W:g} default h_max",
        method,
        substeps=run.substeps[0],
        dE=dE,
        dL=dL,
        att_err=float(np.max(attitude_error(run, q_ref))),
        w_err_rel=float(np.max(np.abs(run.w - w_ref))) / W,
    )


@pytest.mark.parametrize("method", METHODS)
def test_fast_symmetric_top_default_h_max_keeps_its_invariants(free, method):
    """A free symmetric top (2, 2, 3) spun at W = 1e4 with w_perp = 1e-3 W, default
    h_max: |w_perp| is exactly constant (docs/theory.md §2.3; rbcheck.closed_forms.free_symmetric),
    and so is E. 'Never garbage': |w_perp| within 10 % and E within 1e-3 over 1 s (1600
    revolutions) with whatever step the FMU chose."""
    W = 1e4
    run = simulate(free, method, {**principal((2.0, 2.0, 3.0)), **omega0((1e-3 * W, 0, W))}, 1e-2, 100)
    assert run.status == OK
    w_perp = np.hypot(run.out["w_body[1]"], run.out["w_body[2]"])
    dev, dE = float(np.max(np.abs(w_perp / (1e-3 * W) - 1))), rel_drift(run.out["E_kin"])
    report("symmetric top W=1e4 default h_max, 1 s", method, substeps=run.substeps[0], w_perp_dev=dev, dE=dE)
    assert dev <= 0.1 and dE <= 1e-3
