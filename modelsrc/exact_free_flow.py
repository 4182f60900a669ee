r"""Exact flow of the torque-free rigid body as a code-generable CasADi SX graph.

References: E. Celledoni, F. Fassò, N. Säfström, A. Zanna, "The exact computation
of the free rigid body motion and its use in splitting methods", SIAM J. Sci.
Comput. 30(4) (2008) 2084–2112 — [CFSZ]: body angular velocity in Jacobi
elliptic functions; attitude from the conserved world angular momentum plus one
angle that is an elliptic integral of the third kind. NIST DLMF chapters 19 and 22
— [DLMF x.y]. B. C. Carlson, "Numerical computation of real or complex elliptic
integrals", Numer. Algorithms 10 (1995) 13–26 — [C95]. Abramowitz & Stegun
§16.15, §17.3.26 — [A&S]. The formulas below are derived here; where a step is
not textbook (the addition-theorem increments of §3) it is checked numerically in
tests/test_exact_free_flow.py.

Conventions (as in ``modelsrc.quaternion``): ``q = (w, x, y, z)``, scalar first,
rotating body -> world; ``ω`` is the BODY angular velocity [rad/s] and
``q̇ = ½ q ⊗ (0, ω)``; ``I`` are the three principal moments [kg m²] (body axes
= principal axes); ``h`` is the step [s] (any sign, any size).

Only elementary SX operations are used (+ − × ÷, pow of 2, sqrt, sin, cos, tanh,
cosh, sinh, atan, atan2, asin, asinh, atanh, log, floor, fabs, sign, fmin, fmax,
if_else). No rootfinder, no integrator, no Python branching on symbolic values;
every loop runs a fixed number of times. Both branches of every ``if_else`` are
finite for finite inputs (guarded denominators, clamped arguments), so the graph
gives no NaN/Inf for finite ``q, ω, h`` and positive ``I`` (fuzz-tested). The
VALUES are guarded; derivatives (CasADi AD of this graph) are not: they are
infinite e.g. at a pure spin (√ of a zero invariant) or ω = 0.

Method (working frame, Jacobi functions, attitude angle, special functions)
--------------------------------------------------------------------------
§1 Working frame. ``D = |L|² − 2E I_mid`` decides which extreme axis the
   polhode encircles (the largest if ``D > 0``, the smallest if ``D < 0``).
   The moments are ranked symbolically (comparisons, ties broken by index) and
   a signed permutation ``P`` (entries 0/±1, det +1, so ``P ω`` is exact) maps
   the body frame to a working frame with ``J3`` = encircled axis, ``J2`` =
   intermediate, ``J1`` = the other one, and ``w1 ≥ 0``, ``w3 ≥ 0`` (half turns
   about working axes 3 and 1 are symmetries of Euler's equations). Before that,
   ``I`` and ``ω`` are divided by powers of two near ``max I_i`` and ``max|ω_i|``
   (``h`` multiplied by the latter): the flow is invariant under these scalings,
   they are EXACT in floating point, and every internal number becomes O(1).
§2 Angular velocity [CFSZ]::

       w1 = A1 cn(s|m), w2 = A2 sn(s|m), w3 = A3 dn(s|m),  s = λ t + s0,

   with σ = sign(J3 − J2), a = |J3 − J1|, b = |J3 − J2|, c = |J2 − J1| and the
   invariants written as sums of same-sign terms (no cancellation)::

       e3 = σ(2E J3 − |L|²) = J1 a w1² + J2 b w2²,
       e1 = σ(|L|² − 2E J1) = J2 c w2² + J3 a w3²,
       |D| = J3 b w3² − J1 c w1²,
       A1² = e3/(J1 a), A2² = e3/(J2 b), A3² = e1/(J3 a),
       m = c e3/(b e1),  1 − m = a|D|/(b e1)   (1 − m computed on its own, so it
       keeps full relative accuracy near the separatrix),
       λ = σ √(b e1/(J1 J2 J3)).

   (Check: substituting into J1 ẇ1 = (J2 − J3) w2 w3 etc. with
   d/ds (sn, cn, dn) = (cn dn, −sn dn, −m sn cn) gives exactly these λ, A_i, m.)
   ``s0`` is never computed: ``(sn, cn, dn)(s0)`` come from the state
   (``sn0 = √(J2 b) w2/√e3``, ``cn0 = √(J1 a) w1/√e3``, ``dn0 = √(J3 a) w3/√e1``)
   and the state after the step from the addition theorem [DLMF 22.8(i)] with
   ``(sn, cn, dn)(λh)``. ``λh`` is reduced by the half period ``2K`` with
   ``floor`` (``sn, cn`` change sign per half period [DLMF Table 22.4.3]), so
   any ``h`` keeps full accuracy: the error grows only like ε·|ω h|, the
   rounding of the phase itself.
§3 Attitude [CFSZ]. With ``l = J w/|L|`` (unit body angular momentum) and ``P_l``
   the minimal rotation taking ``l`` to ``e3`` (quaternion ∝ ``(1 + l3, l2, −l1, 0)``,
   regular because ``l3 ≥ 0``), ``R(t) = R(0) P_l(0)ᵀ Rz(χ) P_l(t)`` maps ``l(t)`` to
   the fixed ``L_world/|L|`` for every χ, and ``Rᵀ Ṙ = [ω]×`` gives::

       χ̇ = 2E/|L| − (l1 l̇2 − l2 l̇1)/(1 + l3)
         = |L|/J3 + (2E J3 − |L|²)/(J3 (|L| + J3 w3))
         = |L|/J3 + C (|L| − J3 A3 dn s)/(1 − n sn² s),
       C = (J3 − J1)/(J1 J3),  n = −J3 (J2 − J1)/(J1 (J3 − J2))  (≤ 0),

   so ``χ(h) = |L| h/J3 + (C/λ)(|L| ΔΠ − J3 A3 ΔG)``, ``ΔΠ``/``ΔG`` being the
   increments over ``[s0, s0 + λh]`` of ``Π(n; am s | m)`` (third kind) and of
   the elementary ``G = ∫ dφ/(1 − n sin²φ)``. Neither increment is formed as a
   difference of two antiderivatives (that would cost ε·|Π(s0)|·|C L/λ| in χ, i.e.
   1e-8 rad for a symmetric body turning 1e-8 off a transverse axis):
   ``ΔΠ = 2k Π(n|m) + Π(n; am ρ) − κ atan2(X, Y)`` by the addition theorem of the
   third-kind integral (Legendre form of [DLMF 19.26.9]; :func:`_pi_increment`),
   and ``ΔG`` as one ``atan2`` of the angle between two planar vectors whose sine
   is expanded with the addition theorem. ``Π`` is evaluated in Carlson form
   [DLMF 19.25(ii)] ``Π(n; φ) = s R_F(c², d², 1) + (n/3) s³ R_J(c², d², 1, 1 − n s²)``;
   for ``|n| > 1`` through the change of parameter ``n -> m/n`` [DLMF 19.7(iii)]
   (:func:`pi_reduced`), which keeps the 4th argument of ``R_J`` in ``[1, 2]``.
§4 Special functions (fixed iteration counts, justified at the constants).
   * ``sn, cn, dn``: the argument is folded to ``[0, K/2]`` with the quarter-period
     identities [DLMF Table 22.4.3] ``sn(K−v) = cd v, cn(K−v) = k' sd v,
     dn(K−v) = k' nd v``, which keep ``cn``, ``dn`` RELATIVELY accurate near ``K``
     (there they are small when ``m -> 1``). On ``[0, K/2]``: descending Landen /
     AGM [DLMF 22.20(ii)] for ``1 − m ≥ MC_ASC``; otherwise two ascending Landen
     steps [DLMF 22.7(ii)] push ``1 − m`` below 3e-12, where the hyperbolic
     approximation with its first-order correction [A&S 16.15.1–3] is exact to
     rounding (this is the k -> 1 treatment; measured relative error of sn, cn, dn
     ≤ 3e-15 on [0, 0.99 K] for 1 − m from 0.5 down to 1e-60).
   * ``K(m)``: ``π/(2 a_N)`` from the AGM, or through the same two ascending
     steps and [A&S 17.3.26] ``K ≈ Λ + k'²(Λ − 1)/4``, ``Λ = ln(4/k')``.
   * ``R_F``, ``R_J``: Carlson's duplication algorithm with the 5th-order Taylor
     tail [C95], [DLMF 19.36(i)], ``N_CARLSON`` steps.
§5 Special cases, all inside the same graph (``if_else``, both branches finite):
   * steady rotation — ω = 0, sphere, rotation about any axis of an equal-moment
     plane, the exact intermediate-axis equilibrium ``w1 = w3 = 0``, generally
     ``λ² ≤ LAM2_STEADY`` (scaled): ``ω`` constant, ``q ⊗ exp(ω h/2)``;
   * separatrix ``2E I_mid = |L|²`` (``|D|`` at the rounding level of its two
     terms, or ``1 − m < MC_SEP``): no period; ``sn = tanh``, ``cn = dn = sech``
     directly at ``s0 + λh`` with ``s0 = asinh(sn0/cn0)``, and the elementary
     ``Π(n; am u | 1) = (u + √ν atan(√ν tanh u))/(1 + ν)``, ``ν = −n``;
   * ``m = 0`` (``I1 = I2`` about the encircled axis, or a pure spin about it):
     the general formulas stay finite (``n = 0`` makes ``κ = 0``, no 0/0) and
     reduce to circular functions. Any ordering of ``I`` is handled by §1.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca

from .elliptic import (
    EPS,
    LAM2_STEADY,
    MC_ASC,
    MC_SEP,
    PI,
    TINY,
    Expr,
    as_sx,
    ellip_k,
    pi_complete,
    pi_reduced,
    pow2_below,
    triple_reduced,
)
from .quaternion import quat_mul

__all__ = ["exact_free_flow", "exact_free_flow_function"]


# --------------------------------------------------------------------------------------
# The flow
# --------------------------------------------------------------------------------------
def _quat_mul(p: list, q: list) -> list:
    """Hamilton product p ⊗ q of scalar-first quaternions given as 4-lists
    (modelsrc.quaternion.quat_mul, the model's one quaternion product)."""
    return ca.vertsplit(quat_mul(ca.vertcat(*p), ca.vertcat(*q)))


def _min_rot(l1: Expr, l2: Expr, l3: Expr) -> list:
    """Unit quaternion of the minimal rotation taking unit ``l`` (l3 ≥ 0) to e3 (module §3)."""
    qw = 1.0 + l3
    nrm = ca.sqrt(ca.fmax(qw * qw + l1 * l1 + l2 * l2, TINY))
    return [qw / nrm, l2 / nrm, -l1 / nrm, as_sx(0.0)]


def _pi_increment(
    n_nu: Expr, kap: Expr, fac: Expr, snr: Expr, cnr: Expr, sn0: Expr, cn0: Expr, sn1: Expr, cn1: Expr
) -> Expr:
    """Correction term of the addition theorem of the third-kind integral.

    For real u, v and ``n ≤ 0`` (``ν = −n``), writing ``Π(u) = ∫₀^u dt/(1 − n sn² t)``::

        Π(u + v) − Π(u) − Π(v) = −κ atan2(X, Y),
        κ = √(ν/((1 + ν)(m + ν))),  X = √(ν(1 + ν)(m + ν)) sn u sn v sn(u+v),
        Y = 1 + ν (1 − cn u cn v cn(u+v))   (≥ 1).

    This is the Legendre form of Carlson's addition theorem [DLMF 19.26.9–19.26.10]
    (homogenised with ``x = csc²φ − 1`` etc.); there ``Y² = γ − δ`` and the closed form
    of ``Y`` was identified and verified numerically (tests). ``1 − cn cn cn`` is summed
    from non-negative parts ``1 − c = s²/(1 + c)`` (cn u, cn v ≥ 0 here), so neither X
    nor Y suffers cancellation. Returns ``κ atan2(X, Y)``.
    """

    def one_minus(c, s):
        return ca.if_else(c > 0, s * s / (1.0 + ca.fabs(c)), 1.0 - c)

    omc = one_minus(cnr, snr) + cnr * one_minus(cn0, sn0) + cnr * cn0 * one_minus(cn1, sn1)
    X = fac * snr * sn0 * sn1
    Y = 1.0 + n_nu * omc
    return kap * ca.atan2(X, Y)


def exact_free_flow(q: Expr, w: Expr, I: Sequence[Expr], h: Expr) -> tuple[Expr, Expr]:
    """Exact torque-free rigid-body flow over a step ``h`` (CasADi SX, code-generable).

    Parameters
    ----------
    q : (4,) SX — unit quaternion (w, x, y, z), scalar first, body -> world.
    w : (3,) SX — angular velocity in the BODY frame [rad/s].
    I : three SX scalars (or an SX 3-vector) — principal moments [kg m²], > 0, ANY
        order, symbolic (the body axes are the principal axes).
    h : SX scalar — step [s], any sign and size.

    Returns
    -------
    (q_next, w_next) : (4,) SX quaternion (body -> world) and (3,) SX body angular
    velocity [rad/s] after time ``h`` of torque-free motion ``J ω̇ = (Jω) × ω``,
    ``q̇ = ½ q ⊗ (0, ω)``. ``q_next = q ⊗ Δq`` keeps the norm of ``q``.

    Exact up to rounding for every ``h``: the number of half periods is counted with
    ``floor`` and carried by the complete integrals ``K(m)``, ``Π(n|m)``, so the error
    grows only like ε·|ω h| (the conditioning of the phase itself). See the module
    docstring for the method and §5 there for the special cases.
    """
    q = as_sx(q)
    w = as_sx(w)
    I = [as_sx(I[0]), as_sx(I[1]), as_sx(I[2])]
    h = as_sx(h)

    # ---- §1 scaling (the flow is invariant under I -> I/s, ω -> ω/W, h -> W h) ----
    # s and W are powers of two, so the scaled numbers are EXACT (an exactly
    # representable separatrix state stays exactly on the separatrix, etc.).
    Imax = ca.fmax(I[0], ca.fmax(I[1], I[2]))
    Wmax = ca.fmax(ca.fabs(w[0]), ca.fmax(ca.fabs(w[1]), ca.fabs(w[2])))
    Is = pow2_below(Imax)
    W = pow2_below(Wmax)
    Jb = [Ii / Is for Ii in I]
    wb = [w[i] / W for i in range(3)]
    hn = W * h

    # ---- §1 symbolic ranking of the moments (ties broken by index) ----
    def before(j: int, i: int) -> Expr:  # does axis j rank below axis i?
        return (Jb[j] < Jb[i]) if j > i else (Jb[j] <= Jb[i])

    rank = [sum(before(j, i) for j in range(3) if j != i) for i in range(3)]
    d = [[rank[i] == r for r in range(3)] for i in range(3)]  # d[i][r] ∈ {0, 1}
    s = [sum(d[i][r] * Jb[i] for i in range(3)) for r in range(3)]  # sorted moments
    v = [sum(d[i][r] * wb[i] for i in range(3)) for r in range(3)]  # matching ω
    # D = L² − 2E I_mid (module §1): > 0 -> polhode around the largest-moment axis
    Dsort = s[0] * (s[0] - s[1]) * v[0] ** 2 + s[2] * (s[2] - s[1]) * v[2] ** 2
    emax = ca.logic_or(Dsort > 0, ca.logic_and(Dsort == 0, (s[2] - s[1]) >= (s[1] - s[0])))
    # rows of the signed permutation P (working axis k <- body axis i)
    P = [
        [emax * d[i][0] + (1 - emax) * d[i][2] for i in range(3)],
        [d[i][1] for i in range(3)],
        [emax * d[i][2] + (1 - emax) * d[i][0] for i in range(3)],
    ]
    det = (
        P[0][0] * (P[1][1] * P[2][2] - P[1][2] * P[2][1])
        - P[0][1] * (P[1][0] * P[2][2] - P[1][2] * P[2][0])
        + P[0][2] * (P[1][0] * P[2][1] - P[1][1] * P[2][0])
    )
    P[1] = [det * e for e in P[1]]  # proper rotation
    wp = [sum(P[k][i] * wb[i] for i in range(3)) for k in range(3)]
    s3 = ca.if_else(wp[2] < 0, -1.0, 1.0)  # half turn about 1
    s1 = ca.if_else(wp[0] < 0, -1.0, 1.0)  # half turn about 3
    P = [[s1 * e for e in P[0]], [s1 * s3 * e for e in P[1]], [s3 * e for e in P[2]]]
    w1, w2, w3 = [sum(P[k][i] * wb[i] for i in range(3)) for k in range(3)]
    J1, J2, J3 = [sum(P[k][i] * P[k][i] * Jb[i] for i in range(3)) for k in range(3)]
    sig = 2.0 * emax - 1.0  # sign(J3 − J2)

    # ---- §2 invariants, all as same-sign sums (module §2) ----
    a, b, c = ca.fabs(J3 - J1), ca.fabs(J3 - J2), ca.fabs(J2 - J1)
    e3 = J1 * a * w1**2 + J2 * b * w2**2  # σ(2E J3 − L²)
    e1 = J2 * c * w2**2 + J3 * a * w3**2  # σ(L² − 2E J1)
    tD3, tD1 = J3 * b * w3**2, J1 * c * w1**2
    # |L² − 2E J2|; at rounding level of its two terms the state IS on the separatrix
    # (snapping is within the conditioning there, and exact separatrix states get m = 1)
    Dab = ca.if_else(ca.fabs(tD3 - tD1) <= 4.0 * EPS * (tD3 + tD1), 0.0, ca.fmax(tD3 - tD1, 0.0))
    L = ca.sqrt((J1 * w1) ** 2 + (J2 * w2) ** 2 + (J3 * w3) ** 2)
    JJJ = J1 * J2 * J3
    be1 = b * e1
    steady = ca.logic_or(be1 <= LAM2_STEADY * JJJ, ca.logic_and(w1 == 0, w3 == 0))
    be1g = ca.if_else(steady, 1.0, be1)
    ag = ca.if_else(a > 0, a, 1.0)
    bg = ca.if_else(b > 0, b, 1.0)
    e1g = ca.if_else(e1 > 0, e1, 1.0)
    m = ca.fmin(ca.fmax(c * e3 / be1g, 0.0), 1.0)
    mc = ca.fmin(ca.fmax(a * Dab / be1g, 0.0), 1.0)
    nu = J3 * c / (J1 * bg)  # ν = −n ≥ 0
    Nn = -J1 * e3 / (J3 * e1g)  # N = m/n ≤ 0
    swap = nu > 1.0
    beta = 1.0 + m + nu - Nn  # (1 − n)(1 − N)
    tau = ca.sqrt(1.0 + nu)
    kap = ca.sqrt(nu) / ca.sqrt(ca.fmax((1.0 + nu) * (m + nu), TINY))
    fac = ca.sqrt(nu * (1.0 + nu) * (m + nu))
    A1 = ca.sqrt(e3 / (J1 * ag))
    A2 = ca.sqrt(e3 / (J2 * bg))
    A3 = ca.sqrt(e1 / (J3 * ag))
    lam = sig * ca.sqrt(be1g / JJJ)
    C = sig * a / (J1 * J3)
    has3 = e3 > 0
    r3 = ca.sqrt(ca.fmax(e3, TINY))
    sn0 = ca.if_else(has3, ca.sqrt(J2 * b) * w2 / r3, 0.0)
    cn0 = ca.if_else(has3, ca.sqrt(J1 * a) * w1 / r3, 1.0)
    dn0 = ca.fmin(ca.sqrt(J3 * a) * w3 / ca.sqrt(e1g), 1.0)

    # ---- §2 phase advance, reduced by half periods ----
    sep = mc < MC_SEP
    asc = mc < MC_ASC
    mce = ca.fmax(mc, MC_SEP)
    K = ellip_k(m, mce)
    Keff = ca.if_else(sep, 1e300, K)
    Delta = lam * hn
    kr = ca.floor(Delta / (2.0 * Keff) + 0.5)
    # |ρ| ≤ K up to rounding; the clamp only matters when |Δ|/2K > 2^52 (phase unresolvable)
    rho = ca.fmin(ca.fmax(Delta - 2.0 * Keff * kr, -Keff), Keff)
    snr, cnr, dnr = triple_reduced(rho, m, mce, Keff, asc, sep)

    # addition theorem [DLMF 22.8.1–22.8.3], denominator 1 − m sn0² snρ² = dn0² + m sn0² cnρ²
    den = ca.fmax(dn0 * dn0 + m * sn0 * sn0 * cnr * cnr, TINY)
    sn1 = (sn0 * cnr * dnr + snr * cn0 * dn0) / den
    cn1 = (cn0 * cnr - sn0 * snr * dn0 * dnr) / den
    dn1 = (dn0 * dnr - m * sn0 * cn0 * snr * cnr) / den
    # exact separatrix: direct hyperbolic functions at s0 + Δ [DLMF 22.5(ii)]
    s0s = ca.asinh(sn0 / ca.fmax(cn0, TINY))
    s1s = s0s + Delta
    sech1 = 1.0 / ca.cosh(ca.fmin(ca.fabs(s1s), 700.0))
    sn1 = ca.if_else(sep, ca.tanh(s1s), sn1)
    cn1 = ca.if_else(sep, sech1, cn1)
    dn1 = ca.if_else(sep, sech1, dn1)

    # ---- §3 the two integrals over [s0, s0 + Δ] ----
    Pic = pi_complete(-nu, Nn, m, mce, K, swap, beta)
    Pir = pi_reduced(-nu, Nn, m, snr, cnr, dnr, swap, beta)
    rnu = ca.sqrt(nu)
    Pir = ca.if_else(sep, (rho + rnu * ca.atan(rnu * ca.tanh(rho))) / (1.0 + nu), Pir)
    dPi = 2.0 * kr * Pic + Pir - _pi_increment(nu, kap, fac, snr, cnr, sn0, cn0, sn1, cn1)
    # ΔG: angle between (cos φ, τ sin φ) at am s0 and at am(s0 + ρ); its sine
    # sin(ψ − φ) = sn1 cn0 − cn1 sn0 expanded with the addition theorem (no cancellation)
    omd = m * snr * snr / (1.0 + dnr)  # 1 − dnρ
    sin_add = (snr * dn0 * (cn0 * cn0 + sn0 * sn0 * dnr) - sn0 * cn0 * cnr * omd) / den
    sin_pp = ca.if_else(ca.logic_and(sep, ca.fabs(Delta) >= 1.0), sn1 * cn0 - cn1 * sn0, sin_add)
    cos_pp = cn1 * cn0 + (1.0 + nu) * sn1 * sn0
    thd = ca.atan2(tau * sin_pp, cos_pp)
    thd = thd + 2.0 * PI * ca.logic_and(rho > 0, thd < -0.5 * PI) - 2.0 * PI * ca.logic_and(rho < 0, thd > 0.5 * PI)
    dG = (kr * PI + thd) / tau
    lamg = ca.if_else(steady, 1.0, lam)
    chi = L * hn / J3 + (C / lamg) * (L * dPi - J3 * A3 * dG)

    # state after the step in the working frame (sn, cn flip sign per half period)
    sg = 1.0 - 2.0 * (kr - 2.0 * ca.floor(0.5 * kr))
    W1, W2, W3 = A1 * sg * cn1, A2 * sg * sn1, A3 * dn1

    # ---- §3 attitude: R(h) = R(0) Pᵀ [P_l(0)ᵀ Rz(χ) P_l(h)] P ----
    Lg = ca.fmax(L, TINY)
    p0 = _min_rot(J1 * w1 / Lg, J2 * w2 / Lg, J3 * w3 / Lg)
    p1 = _min_rot(J1 * W1 / Lg, J2 * W2 / Lg, J3 * W3 / Lg)
    qz = [ca.cos(0.5 * chi), as_sx(0.0), as_sx(0.0), ca.sin(0.5 * chi)]
    dl = _quat_mul(_quat_mul([p0[0], -p0[1], -p0[2], -p0[3]], qz), p1)
    dv_body = [sum(P[k][i] * dl[k + 1] for k in range(3)) for i in range(3)]  # Pᵀ δ_vec

    # steady rotation: Δq = exp(ω h/2) in the body frame
    wn = ca.sqrt(wb[0] ** 2 + wb[1] ** 2 + wb[2] ** 2)
    half = 0.5 * wn * hn
    sfac = ca.if_else(wn > 0, ca.sin(half) / ca.fmax(wn, TINY), 0.0)
    dq = [ca.if_else(steady, ca.cos(half), dl[0])] + [ca.if_else(steady, sfac * wb[i], dv_body[i]) for i in range(3)]

    qn = _quat_mul([q[0], q[1], q[2], q[3]], dq)
    ww = [W1, W2, W3]
    w_next = [ca.if_else(steady, w[i], W * sum(P[k][i] * ww[k] for k in range(3))) for i in range(3)]
    out = ca.cse(ca.vertcat(*qn, *w_next))  # merge the repeated AGM/Landen sequences
    return out[0:4], out[4:7]


def exact_free_flow_function(name: str = "exact_free_flow") -> ca.Function:
    """``ca.Function`` (q[4], w[3], I[3], h) -> (q_next[4], w_next[3]) of :func:`exact_free_flow`."""
    q = ca.SX.sym("q", 4)
    w = ca.SX.sym("w", 3)
    I = ca.SX.sym("I", 3)
    h = ca.SX.sym("h")
    qn, wn = exact_free_flow(q, w, [I[0], I[1], I[2]], h)
    return ca.Function(name, [q, w, I, h], [qn, wn], ["q", "w", "I", "h"], ["q_next", "w_next"])
