"""Tests of modelsrc.exact_free_flow (exact torque-free flow as a CasADi SX graph).

The SX expression is evaluated numerically through ``casadi.Function`` and compared
with independent references:

* ``rbcheck.closed_forms.free_asymmetric.solve`` / ``rbcheck.closed_forms.free_symmetric.solve`` (closed forms
  written with scipy's elliptic functions, not with this module);
* scipy ``solve_ivp`` (DOP853, rtol = atol = 1e-13) on Euler's equations
  ``J ω̇ = (J ω) × ω`` plus ``q̇ = ½ q ⊗ (0, ω)`` (written here);
* scipy's Carlson integrals / ellipj / ellipk, quadrature, and exact special values
  (``sn, cn, dn`` at ``K/2``) for the helpers.

Attitudes are compared as rotation matrices (q and −q are the same rotation);
angular velocities relative to |ω|. Units: I in kg m², ω in rad/s, h in s.
The generated C is compiled once with gcc and called through ctypes.
"""

from __future__ import annotations

import ctypes
import itertools
import shutil
import subprocess
import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import IntegrationWarning, quad, solve_ivp
from scipy.special import ellipj, ellipk, ellipkm1, elliprf, elliprj

from modelsrc.elliptic import carlson_rf, carlson_rj, ellip_k, ellip_pi_amplitude, ellip_pi_complete, jacobi_sn_cn_dn
from modelsrc.exact_free_flow import exact_free_flow, exact_free_flow_function
from rbcheck.closed_forms import free_asymmetric, free_symmetric
from rbcheck.numerics.rotation_np import matrix_to_quat, quat_conj, quat_from_axis_angle, quat_mul, quat_to_matrix

F = exact_free_flow_function()
_PERMS = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]


# ----------------------------------------------------------------------------- helpers
def flow(q, w, I, h):
    """Evaluate the SX flow numerically: (q_next (4,), w_next (3,))."""
    qn, wn = F(np.asarray(q, float), np.asarray(w, float), np.asarray(I, float), float(h))
    return np.array(qn).ravel(), np.array(wn).ravel()


def flow_batch(q, w, I, h):
    """Columns are cases: q (4, n), w (3, n), I (3, n), h (n,)."""
    qn, wn = F.map(q.shape[1])(q, w, I, h)
    return np.array(qn), np.array(wn)


def ode(q, w, I, h):
    """Reference: DOP853 (rtol = atol = 1e-13) on Euler's equations + quaternion kinematics."""
    I = np.asarray(I, float)

    def rhs(_t, y):
        qw, qx, qy, qz, w1, w2, w3 = y
        return [
            0.5 * (-qx * w1 - qy * w2 - qz * w3),
            0.5 * (qw * w1 + qy * w3 - qz * w2),
            0.5 * (qw * w2 - qx * w3 + qz * w1),
            0.5 * (qw * w3 + qx * w2 - qy * w1),
            (I[1] - I[2]) * w2 * w3 / I[0],
            (I[2] - I[0]) * w3 * w1 / I[1],
            (I[0] - I[1]) * w1 * w2 / I[2],
        ]

    sol = solve_ivp(rhs, (0.0, h), np.r_[q, w], method="DOP853", rtol=1e-13, atol=1e-13)
    assert sol.success
    return sol.y[:4, -1], sol.y[4:, -1]


def errs(qa, wa, qb, wb, wscale):
    """(max |R_a − R_b|, max |ω_a − ω_b| / wscale); inf if anything is not finite."""
    e = (
        float(np.max(np.abs(quat_to_matrix(qa) - quat_to_matrix(qb)))),
        float(np.max(np.abs(np.asarray(wa) - np.asarray(wb)))) / wscale,
    )
    return e if np.all(np.isfinite(e)) else (np.inf, np.inf)


def rand_q(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def sym_reference(I, w, q, h, ax):
    """free_symmetric.solve for a body symmetric about body axis ``ax`` (cyclic relabelling)."""
    perm = [(ax + 1) % 3, (ax + 2) % 3, ax]
    P = np.eye(3)[perm]  # proper (cyclic) permutation, v_p = P v
    qP = matrix_to_quat(P)
    wr, qr = free_symmetric.solve(I[perm][0], I[perm][2], P @ w, quat_mul(q, quat_conj(qP)), [h])
    return quat_mul(qr[0], qP), P.T @ wr[0]


def near_separatrix_state(I, mc, side):
    """ω in the sorted frame (I1 < I2 < I3) with 1 − k² = mc on the given polhode side."""
    J1, J2, J3 = I
    a, b, c = J3 - J1, J3 - J2, J2 - J1
    w1, w2 = 1.0, 0.7
    w3 = np.sqrt(J1 * c * w1**2 / (J3 * b))
    for _ in range(6):  # 1 − m = a|D|/(b e1), D = J3 b w3² − J1 c w1²
        e1 = J2 * c * w2**2 + J3 * a * w3**2
        w3 = np.sqrt((J1 * c * w1**2 + side * mc * b * e1 / a) / (J3 * b))
    return np.array([w1, w2, w3])


def report(name, values):
    print(f"[exact_free_flow] {name}: " + ", ".join(f"{k}={v:.1e}" for k, v in values.items()))


# ----------------------------------------------------------------------------- helpers: special functions
def test_carlson_integrals_match_scipy():
    x, y, z, p = (ca.SX.sym(s) for s in "xyzp")
    frf = ca.Function("rf", [x, y, z], [carlson_rf(x, y, z)])
    frj = ca.Function("rj", [x, y, z, p], [carlson_rj(x, y, z, p)])
    rng = np.random.default_rng(1)
    n = 300
    X = rng.uniform(0, 1, n) * 10.0 ** rng.uniform(-200, 0, n)
    Y = rng.uniform(0, 1, n) * 10.0 ** rng.uniform(-30, 0, n)
    Z = rng.uniform(0.1, 2.0, n)
    P = rng.uniform(0.05, 3.0, n)  # includes p < max(x, y, z) (the atanh branch of R_C)
    erf_ = np.abs(np.array(frf.map(n)(X, Y, Z)).ravel() / elliprf(X, Y, Z) - 1)
    erj_ = np.abs(np.array(frj.map(n)(X, Y, Z, P)).ravel() / elliprj(X, Y, Z, P) - 1)
    report("R_F, R_J rel. err vs scipy", {"RF": erf_.max(), "RJ": erj_.max()})
    assert erf_.max() < 4e-15 and erj_.max() < 4e-15
    # the near-separatrix complete cases that set N_CARLSON: R_F(0, mc, 1) = K(1 − mc)
    mc = 10.0 ** np.array([-1.0, -8, -16, -50, -100, -200, -280])
    k_ref = np.log(4 / np.sqrt(mc)) + mc / 4 * (np.log(4 / np.sqrt(mc)) - 1)  # A&S 17.3.26
    k_ref[:3] = ellipkm1(mc[:3])
    got = np.array(frf.map(7)(0.0, mc, 1.0)).ravel()
    assert np.max(np.abs(got / k_ref - 1)) < 2e-15


def test_jacobi_functions():
    u, m, mc = ca.SX.sym("u"), ca.SX.sym("m"), ca.SX.sym("mc")
    fj = ca.Function("j", [u, m, mc], list(jacobi_sn_cn_dn(u, m, mc)))
    fk = ca.Function("k", [m, mc], [ellip_k(m, mc)])
    rng = np.random.default_rng(2)
    # (a) moderate m, any u (many periods): absolute accuracy vs scipy.special.ellipj
    n = 400
    M = rng.uniform(0, 0.999, n)
    U = rng.uniform(-1, 1, n) * ellipk(M) * rng.choice([1, 10, 1000], n)
    got = np.array(ca.vertcat(*fj.map(n)(U, M, 1 - M)))
    ref = np.array(ellipj(U, M)[:3])
    err_a = np.max(np.abs(got - ref) / (1 + np.abs(U)))  # the argument itself is ±ε|u|
    # (b) exact values at the quarter period's half [DLMF 22.5.2]: sn(K/2) = 1/sqrt(1 + k'),
    #     cn(K/2) = sqrt(k'/(1 + k')), dn(K/2) = sqrt(k'); RELATIVE accuracy down to 1 − m = 1e-200
    MC = 10.0 ** np.array([-0.3, -1, -2, -3, -6, -9, -10, -12, -16, -30, -100, -200])
    K = np.array(fk.map(MC.size)(1 - MC, MC)).ravel()
    got = np.array(ca.vertcat(*fj.map(MC.size)(K / 2, 1 - MC, MC)))
    kp = np.sqrt(MC)
    ref = np.array([1 / np.sqrt(1 + kp), np.sqrt(kp / (1 + kp)), np.sqrt(kp)])
    err_b = np.max(np.abs(got / ref - 1))
    # (c) K against scipy (ellipkm1 is accurate for small 1 − m)
    err_k = np.max(np.abs(K[:9] / ellipkm1(MC[:9]) - 1))
    # (d) exact separatrix m = 1: tanh, sech, sech
    s, c, d = (float(v) for v in fj(3.7, 1.0, 0.0))
    err_s = max(abs(s - np.tanh(3.7)), abs(c - 1 / np.cosh(3.7)), abs(d - 1 / np.cosh(3.7)))
    report(
        "sn/cn/dn",
        {"abs/(1+|u|) (moderate m)": err_a, "rel at K/2 (mc to 1e-200)": err_b, "K rel": err_k, "m=1": err_s},
    )
    assert err_a < 2e-15 and err_b < 1e-14 and err_k < 1e-15 and err_s < 3e-16


def test_third_kind_integrals():
    n_, m_, s_, c_, d_ = (ca.SX.sym(v) for v in ("n", "m", "s", "c", "d"))
    fpc = ca.Function("pc", [n_, m_], [ellip_pi_complete(n_, m_)])
    fpa = ca.Function("pa", [n_, m_, s_, c_, d_], [ellip_pi_amplitude(n_, m_, s_, c_, d_)])
    worst_c = worst_a = 0.0
    for n in (0.0, -0.3, -0.99, -1.5, -40.0, -1e6):  # |n| > 1 goes through n -> m/n
        for m in (0.0, 0.3, 0.9, 1 - 1e-8):
            # quadrature reference: the plain Carlson sum R_F + n/3 R_J cancels for n << −1
            # (scipy's elliprf/elliprj give 3e-12 relative error at n = −1e6; this module
            # goes through n -> m/n and stays at ~1e-16)
            def integrand(t, n=n, m=m):
                return 1 / ((1 - n * np.sin(t) ** 2) * np.sqrt(1 - m * np.sin(t) ** 2))

            def integral(phi, n=n, m=m):  # split at the peak width 1/sqrt(1 − n) near 0
                cuts = sorted({0.0, phi, min(phi, 8.0 / np.sqrt(1.0 - n))})
                return sum(
                    quad(integrand, lo, hi, epsabs=0, epsrel=2e-14, limit=200)[0] for lo, hi in itertools.pairwise(cuts)
                )

            # complete: ∫_0^K du/(1 − n sn²u) (smooth in u; split at the peak near 0)
            Kc, cut = ellipk(m), min(ellipk(m), 8.0 / np.sqrt(1.0 - n))
            ref = sum(
                quad(lambda u: 1 / (1 - n * ellipj(u, m)[0] ** 2), lo, hi, epsabs=0, epsrel=2e-14, limit=200)[0]
                for lo, hi in ((0.0, cut), (cut, Kc))
                if hi > lo
            )
            worst_c = max(worst_c, abs(float(fpc(n, m)) / ref - 1))
            for phi in (0.2, 1.0, 1.5):
                ref = integral(phi)
                got = float(fpa(n, m, np.sin(phi), np.cos(phi), np.sqrt(1 - m * np.sin(phi) ** 2)))
                worst_a = max(worst_a, abs(got / ref - 1))
    report("Pi rel. err", {"complete": worst_c, "incomplete": worst_a})
    assert worst_c < 1e-14 and worst_a < 1e-13


def test_third_kind_addition_theorem():
    """Π(u+v) − Π(u) − Π(v) = −κ atan2(X, Y) (the increment formula of module §3), with
    Π(u) = ∫₀^u dt/(1 − n sn²t), against quadrature; |u|, |v| ≤ K, n ≤ 0, any m."""
    from modelsrc.exact_free_flow import _pi_increment

    args = [ca.SX.sym(v) for v in ("nu", "kap", "fac", "sv", "cv", "su", "cu", "sw", "cw")]
    finc = ca.Function("inc", args, [_pi_increment(*args)])
    rng = np.random.default_rng(13)
    worst = 0.0
    for _ in range(40):
        m = rng.uniform(0, 1) ** rng.choice([1, 6])
        nu = 10.0 ** rng.uniform(-3, 3)
        K = ellipk(m)
        u, v = rng.uniform(-K, K, 2)
        su, cu, _, _ = ellipj(u, m)
        sv, cv, _, _ = ellipj(v, m)
        sw, cw, _, _ = ellipj(u + v, m)

        def pi_u(a, b):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", IntegrationWarning)
                return quad(lambda t: 1 / (1 + nu * ellipj(t, m)[0] ** 2), a, b, epsabs=1e-15, epsrel=1e-14, limit=200)[
                    0
                ]

        ref = pi_u(u, u + v) - pi_u(0, v)
        kap = np.sqrt(nu / ((1 + nu) * (m + nu)))
        fac = np.sqrt(nu * (1 + nu) * (m + nu))
        got = -float(finc(nu, kap, fac, sv, cv, su, cu, sw, cw))
        worst = max(worst, abs(got - ref))
    report("addition theorem of Pi (abs err)", {"max": worst})
    assert worst < 1e-13


# ----------------------------------------------------------------------------- the flow
def test_asymmetric_vs_closed_form_all_orderings_both_polhodes_any_step():
    """All 6 orderings of I, both polhode families, h|ω| from 1e-3 to 1e4, vs rbcheck."""
    rng = np.random.default_rng(3)
    worst = {}
    for hw in (1e-3, 1e-1, 1.0, 10.0, 1e2, 1e3, 1e4):
        eq = ew = 0.0
        for perm in _PERMS:
            for side in (+1, -1):
                while True:  # polhode around the max / min axis
                    I = np.sort(rng.uniform(0.5, 3.0, 3))
                    w = rng.normal(size=3)
                    if np.sign(np.sum(I * (I - I[1]) * w**2)) == side:  # L² − 2E I_mid
                        break
                w = w / np.linalg.norm(w)
                I, w = I[list(perm)], w[list(perm)]
                q = rand_q(rng)
                q1, w1 = flow(q, w, I, hw)
                wr, qr = free_asymmetric.solve(I, w, q, [hw])
                e = errs(q1, w1, qr[0], wr[0], 1.0)
                eq, ew = max(eq, e[0]), max(ew, e[1])
        worst[f"h|w|={hw:g}"] = max(eq, ew)
        # the phase itself is only known to ~ε·h|ω|; allow a few ulp of it
        assert max(eq, ew) < 2e-14 + 1e-15 * hw, (hw, eq, ew)
    report("vs rbcheck.closed_forms.free_asymmetric (max of R, w errors)", worst)


def test_asymmetric_vs_ode():
    rng = np.random.default_rng(4)
    eq = ew = 0.0
    for k in range(8):
        I = rng.uniform(0.3, 3.0, 3)
        w = rng.normal(size=3) * 2.0
        q = rand_q(rng)
        h = 5.0 / np.linalg.norm(w) * (k + 1) / 4
        q1, w1 = flow(q, w, I, h)
        q2, w2 = ode(q, w, I, h)
        e = errs(q1, w1, q2, w2, np.linalg.norm(w))
        eq, ew = max(eq, e[0]), max(ew, e[1])
    report("vs DOP853", {"R": eq, "w": ew})
    assert eq < 2e-12 and ew < 2e-12


@pytest.mark.parametrize("mc", [1e-4, 1e-7, 1e-10])
def test_near_separatrix(mc):
    """1 − k² down to 1e-10 on both sides of the separatrix, axes permuted, vs DOP853 and rbcheck."""
    rng = np.random.default_rng(5)
    eo = er = 0.0
    for side in (+1, -1):
        for perm in ((0, 1, 2), (2, 0, 1)):
            I = np.array([1.0, 2.0, 3.5])
            w = near_separatrix_state(I, mc, side)
            I, w = I[list(perm)], w[list(perm)]
            q = rand_q(rng)
            h = 5.0 / np.linalg.norm(w)
            q1, w1 = flow(q, w, I, h)
            q2, w2 = ode(q, w, I, h)
            eo = max(eo, *errs(q1, w1, q2, w2, np.linalg.norm(w)))
            wr, qr = free_asymmetric.solve(I, w, q, [h])
            er = max(er, *errs(q1, w1, qr[0], wr[0], np.linalg.norm(w)))
    report(f"near separatrix 1-k^2={mc:g}", {"vs DOP853": eo, "vs rbcheck": er})
    assert eo < 2e-12 and er < 1e-12


def test_exact_separatrix():
    """2 E I2 = |L|² exactly (I = (1, 1.5, 3), ω = (±3, ω2, 1)): k = 1, hyperbolic functions."""
    rng = np.random.default_rng(6)
    eo = er = 0.0
    for w2 in (0.5, -1.0, 2.0):
        for s1 in (1.0, -1.0):
            for perm in ((0, 1, 2), (1, 2, 0), (2, 1, 0)):
                I = np.array([1.0, 1.5, 3.0])[list(perm)]
                w = np.array([3.0 * s1, w2, 1.0])[list(perm)]
                q = rand_q(rng)
                q1, w1 = flow(q, w, I, 2.0)
                q2, w2_ = ode(q, w, I, 2.0)
                eo = max(eo, *errs(q1, w1, q2, w2_, np.linalg.norm(w)))
                wr, qr = free_asymmetric.solve(I, w, q, [2.0, 10.0, 100.0])  # (NaN from ~300 on)
                for j, h in enumerate((2.0, 10.0, 100.0)):
                    qa, wa = flow(q, w, I, h)
                    er = max(er, *errs(qa, wa, qr[j], wr[j], np.linalg.norm(w)))
    report("exact separatrix", {"vs DOP853 (h=2)": eo, "vs rbcheck (h<=100)": er})
    assert eo < 2e-12 and er < 5e-13  # |ω|h ≈ 300 rad at h = 100


def test_near_symmetric():
    """I2 − I1 = 1e-9 I1 for each pair (incl. the |n| >> 1 case J3 ≈ J2), vs DOP853."""
    rng = np.random.default_rng(7)
    worst = 0.0
    for base in ((1.0, 1.0 + 1e-9, 2.0), (1.0, 2.0, 2.0 * (1 + 1e-9)), (2.0, 1.0, 1.0 + 1e-9)):
        I = np.array(base)
        for k in range(3):
            w = rng.normal(size=3)
            if k == 2:  # polhode around an axis of the near-equal pair: |n| ~ 1e9
                far = int(np.argmax(np.abs(I - np.median(I))))
                w[far] *= 1e-5
            q = rand_q(rng)
            h = 3.0 / np.linalg.norm(w)
            q1, w1 = flow(q, w, I, h)
            q2, w2 = ode(q, w, I, h)
            worst = max(worst, *errs(q1, w1, q2, w2, np.linalg.norm(w)))
    report("near symmetric (1e-9)", {"vs DOP853": worst})
    assert worst < 2e-12


def test_needles_down_to_the_smallest_moment_accepted():
    """A needle I = (ε, 1, 1) along each body axis, ε from 1e-2 down to the smallest moment
    the FMU accepts (modelsrc.model.POSITIVE_MIN = 1e-100), vs DOP853 (rtol = atol = 1e-13).
    Before issue 23.3 the attitude angle χ was formed as L h/J3 + C L ΔΠ/λ, two terms of size
    L h/ε that cancel to L h/J1: errors 6.4e-6 at ε = 1e-12, 3e-4 at 1e-14, 0.06 at 1e-16.
    Bound as test_near_symmetric (2e-12, the reference's own accuracy over these steps); the
    flow's conditioning is ε_mach |ω h| ≤ 1e-14 here, and ε enters nowhere (the transverse
    moments are equal, so the needle's own spin does not couple into ω)."""
    from modelsrc.model import POSITIVE_MIN

    rng = np.random.default_rng(23)
    worst: dict[str, float] = {}
    for k in [*range(2, 17, 2), 30, 100]:
        eps = 10.0**-k
        assert eps >= POSITIVE_MIN
        for ax in range(3):
            for w0 in (np.array([0.05, 12.0, 0.05]), rng.normal(size=3) * 3.0):
                I = np.ones(3)
                I[ax] = eps
                w = np.roll(w0, ax)
                q = rand_q(rng)
                for h in (0.01, 3.0 / np.linalg.norm(w)):
                    q1, w1 = flow(q, w, I, h)
                    q2, w2 = ode(q, w, I, h)
                    e = max(errs(q1, w1, q2, w2, np.linalg.norm(w)))
                    worst[f"1e-{k}"] = max(worst.get(f"1e-{k}", 0.0), e)
    report("needles (eps, 1, 1) vs DOP853", worst)
    assert max(worst.values()) < 2e-12, worst


def test_exact_symmetric_any_axis_and_transverse_spin():
    """I1 = I2 (k = 0): vs rbcheck.closed_forms.free_symmetric, symmetry axis on each body axis; also the
    nearly transverse spin where the body-frame precession rate λ -> 0 (no 1/λ blow-up)."""
    rng = np.random.default_rng(8)
    worst = {"short": 0.0, "h|w|=1e3": 0.0, "transverse": 0.0}
    for ax in range(3):
        for ratio in (0.5, 2.0):
            I = np.full(3, 1.3)
            I[ax] *= ratio
            for hw, key in ((1.0, "short"), (1e3, "h|w|=1e3")):
                w = rng.normal(size=3)
                w /= np.linalg.norm(w)
                q = rand_q(rng)
                q1, w1 = flow(q, w, I, hw)
                qr, wr = sym_reference(I, w, q, hw, ax)
                worst[key] = max(worst[key], *errs(q1, w1, qr, wr, 1.0))
    for eps in (1e-4, 1e-8, 1e-12, 1e-15, 1e-30, 0.0):
        for hw in (1.0, 100.0):
            I = np.array([1.0, 1.0, 2.0])
            w = np.array([0.6, 0.8, eps])
            q = rand_q(rng)
            q1, w1 = flow(q, w, I, hw)
            qr, wr = sym_reference(I, w, q, hw, 2)
            worst["transverse"] = max(worst["transverse"], *errs(q1, w1, qr, wr, 1.0))
    report("exact symmetric", worst)
    assert worst["short"] < 1e-14 and worst["h|w|=1e3"] < 1e-12 and worst["transverse"] < 1e-13


def test_steady_cases_sphere_zero_pure_spin():
    """Sphere, ω = 0, pure principal spins (min, mid, max axis, both signs) and spin in an
    equal-moment plane: ω constant and q ⊗ exp(ω h/2), to rounding."""
    rng = np.random.default_rng(9)
    cases = [((2, 2, 2), (0.3, -0.2, 0.5)), ((1, 2, 3), (0, 0, 0)), ((3, 1, 2), (0, 0, 0))]
    for I in ((1, 2, 3), (3, 1, 2), (2, 3, 1)):
        for ax in range(3):
            for sgn in (1.0, -1.0):
                w = np.zeros(3)
                w[ax] = 1.7 * sgn
                cases.append((I, tuple(w)))
    cases += [((1, 1, 2), (0.3, 0.4, 0)), ((1, 2, 2), (0, 0.3, 0.4)), ((2, 1, 2), (0.3, 0, -0.4))]
    worst = 0.0
    for I, w in cases:
        I, w = np.array(I, float), np.array(w, float)
        q = rand_q(rng)
        for h in (0.3, 7.0, 1e4):
            q1, w1 = flow(q, w, I, h)
            wn = np.linalg.norm(w)
            qr = quat_mul(q, quat_from_axis_angle(w / wn if wn > 0 else np.zeros(3), wn * h))
            e = errs(q1, w1, qr, w, 1.0)
            # a pure spin about the encircled axis runs through the general formulas: its
            # phase |ω|h carries ~1 ulp, i.e. ≤ 2.3e-16·|ω|h
            worst = max(worst, e[0] / (4e-15 + 4e-16 * wn * h), e[1] / 4e-15)
    report("steady cases", {"max err / (4e-15 + 4e-16 |w|h)": worst})
    assert worst < 1.0


def test_invariants_and_no_nan_fuzz():
    """Random (also extreme) inputs: finite output, world angular momentum and energy kept."""
    rng = np.random.default_rng(10)
    n = 4000
    I = 10.0 ** rng.uniform(-4, 4, (3, n))
    kind = rng.integers(0, 8, n)
    I[1, kind == 1] = I[0, kind == 1]  # symmetric
    I[:, kind == 2] = I[0, kind == 2]  # sphere
    I[1, kind == 3] = I[0, kind == 3] * (1 + 1e-12)  # near symmetric
    w = rng.normal(size=(3, n)) * 10.0 ** rng.uniform(-100, 100, n)
    w[rng.integers(0, 4, (3, n)) == 0] = 0.0  # zero components / pure spins
    w[:, kind == 4] = 0.0
    hw = 10.0 ** rng.uniform(-5, 4, n)
    h = rng.choice([-1.0, 1.0], n) * hw / np.maximum(np.linalg.norm(w, axis=0), 1e-300)
    q = rng.normal(size=(4, n))
    q /= np.linalg.norm(q, axis=0)
    qn, wn = flow_batch(q, w, I, h)
    assert np.all(np.isfinite(qn)) and np.all(np.isfinite(wn))
    assert np.max(np.abs(np.linalg.norm(qn, axis=0) - 1)) < 1e-15
    ok = np.linalg.norm(w, axis=0) > 0
    s = np.max(np.abs(w[:, ok]), axis=0)  # scale out before squaring
    R0, R1 = quat_to_matrix(q[:, ok].T), quat_to_matrix(qn[:, ok].T)
    L0 = np.einsum("nij,nj->ni", R0, (I[:, ok] * w[:, ok] / s).T)
    L1 = np.einsum("nij,nj->ni", R1, (I[:, ok] * wn[:, ok] / s).T)
    dL = np.linalg.norm(L1 - L0, axis=1) / np.linalg.norm(L0, axis=1)
    E0 = np.sum(I[:, ok] * (w[:, ok] / s) ** 2, axis=0)
    E1 = np.sum(I[:, ok] * (wn[:, ok] / s) ** 2, axis=0)
    dE = np.abs(E1 / E0 - 1)
    report("invariants (random, extreme)", {"|dL_world|/|L|": dL.max(), "dE/E": dE.max()})
    assert dL.max() < 5e-15 and dE.max() < 5e-15


def test_composition():
    """Φ(h1) ∘ Φ(h2) = Φ(h1 + h2) (h1, h2 binary fractions: h1 + h2 is exact)."""
    rng = np.random.default_rng(11)
    worst = {}
    for hw in (1.0, 10.0, 1e3):
        e = 0.0
        for _ in range(12):
            I = rng.uniform(0.3, 3.0, 3)
            if rng.uniform() < 0.25:
                I[1] = I[0]
            w = rng.normal(size=3)
            w /= np.linalg.norm(w)
            q = rand_q(rng)
            h1 = np.round(rng.uniform(0, hw) * 1024) / 1024
            h2 = hw - h1
            qa, wa = flow(q, w, I, hw)
            qb, wb = flow(*flow(q, w, I, h1), I, h2)
            qc, wc = flow(*flow(q, w, I, hw), I, -hw)  # Φ(−h) ∘ Φ(h) = id
            e = max(e, *errs(qa, wa, qb, wb, 1.0), *errs(qc, wc, q, w, 1.0))
        worst[f"h|w|={hw:g}"] = e
    report("composition", worst)
    assert worst["h|w|=1"] < 1e-13 and worst["h|w|=10"] < 1e-13 and worst["h|w|=1000"] < 2e-12


# ----------------------------------------------------------------------------- code generation
@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not available")
def test_generated_c_matches_and_timing(tmp_path: Path):
    """casadi.CodeGenerator -> gcc -O2 -std=c99 -> ctypes: same numbers, and ns per call."""
    q, w, I, h = ca.SX.sym("q", 4), ca.SX.sym("w", 3), ca.SX.sym("I", 3), ca.SX.sym("h")
    qn, wn = exact_free_flow(q, w, [I[0], I[1], I[2]], h)
    fun = ca.Function("eff", [q, w, I, h], [qn, wn])
    cg = ca.CodeGenerator("eff.c", {"with_header": False, "casadi_int": "long long int"})
    cg.add(fun)
    cg.generate(str(tmp_path) + "/")
    (tmp_path / "bench.c").write_text(r"""
#include <time.h>
int eff(const double** arg, double** res, long long int* iw, double* w, int mem);
static double work[1024];
int eff_call(const double* q, const double* om, const double* I, double h, double* qo, double* wo) {
    const double* arg[4] = {q, om, I, &h}; double* res[2] = {qo, wo};
    return eff(arg, res, 0, work, 0);
}
double eff_bench(int n, const double* q, const double* om, const double* I, double h,
                 double* qo, double* wo) {
    struct timespec t0, t1; int i;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (i = 0; i < n; ++i) eff_call(q, om, I, h * (1.0 + 1e-9 * i), qo, wo);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    return ((t1.tv_sec - t0.tv_sec) * 1e9 + (t1.tv_nsec - t0.tv_nsec)) / n;
}
""")
    assert fun.sz_w() <= 1024
    so = tmp_path / "eff.so"
    subprocess.run(
        [
            "gcc",
            "-O2",
            "-std=c99",
            "-D_POSIX_C_SOURCE=199309L",
            "-shared",
            "-fPIC",
            "-o",
            str(so),
            str(tmp_path / "eff.c"),
            str(tmp_path / "bench.c"),
            "-lm",
        ],
        check=True,
        capture_output=True,
    )
    lib = ctypes.CDLL(str(so))
    dp = ctypes.POINTER(ctypes.c_double)
    lib.eff_call.restype = ctypes.c_int
    lib.eff_bench.restype = ctypes.c_double

    def c_flow(qv, wv, Iv, hv):
        qv, wv, Iv = (np.ascontiguousarray(v, dtype=float) for v in (qv, wv, Iv))
        qo, wo = np.zeros(4), np.zeros(3)
        assert (
            lib.eff_call(
                qv.ctypes.data_as(dp),
                wv.ctypes.data_as(dp),
                Iv.ctypes.data_as(dp),
                ctypes.c_double(hv),
                qo.ctypes.data_as(dp),
                wo.ctypes.data_as(dp),
            )
            == 0
        )
        return qo, wo

    rng = np.random.default_rng(12)
    cases = [(rand_q(rng), rng.normal(size=3), rng.uniform(0.5, 3, 3), 10.0 ** rng.uniform(-3, 4)) for _ in range(20)]
    cases += [
        (rand_q(rng), np.array(w, float), np.array(I, float), 3.0)
        for I, w in (
            ((1, 1.5, 3), (3, 0.5, 1)),
            ((1, 1, 2), (0.6, 0.8, 1e-12)),
            ((2, 2, 2), (1, 2, 3)),
            ((1, 2, 3), (0, 0, 0)),
            ((1, 2, 3), (0, 1, 0)),
            ((1, 2, 2 + 4e-9), (1e-5, 0.3, 0.9)),
        )
    ]
    worst = 0.0
    for qv, wv, Iv, hv in cases:
        qp, wp = flow(qv, wv, Iv, hv)
        qc, wc = c_flow(qv, wv, Iv, hv)
        worst = max(
            worst, float(np.max(np.abs(qp - qc))), float(np.max(np.abs(wp - wc))) / max(np.linalg.norm(wv), 1e-300)
        )
    qv, wv, Iv = (np.ascontiguousarray(v) for v in (cases[0][0], cases[0][1], cases[0][2]))
    qo, wo = np.zeros(4), np.zeros(3)
    ns = lib.eff_bench(
        20000,
        qv.ctypes.data_as(dp),
        wv.ctypes.data_as(dp),
        Iv.ctypes.data_as(dp),
        ctypes.c_double(2.0),
        qo.ctypes.data_as(dp),
        wo.ctypes.data_as(dp),
    )
    print(
        f"[exact_free_flow] generated C: {fun.n_instructions()} SX instructions, "
        f"work {fun.sz_w()} doubles, {ns:.0f} ns per call (gcc -O2); max |C − Python| = {worst:.1e}"
    )
    assert worst < 1e-14
