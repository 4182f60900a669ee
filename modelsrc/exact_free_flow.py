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
   (:func:`_pi_reduced`), which keeps the 4th argument of ``R_J`` in ``[1, 2]``.
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

import math
from typing import Sequence

import casadi as ca

from .quaternion import quat_mul

__all__ = [
    "exact_free_flow",
    "exact_free_flow_function",
    "carlson_rf",
    "carlson_rj",
    "rc_one",
    "jacobi_agm",
    "jacobi_sn_cn_dn",
    "ellip_k",
    "ellip_pi_complete",
    "ellip_pi_amplitude",
    "N_AGM",
    "N_CARLSON",
    "MC_ASC",
    "MC_SEP",
]

# --------------------------------------------------------------------------------------
# Fixed iteration counts and switch points (see the docstrings of the helpers for the
# derivations; measured worst cases are in tests/test_exact_free_flow.py).
# --------------------------------------------------------------------------------------
#: Descending-Landen (AGM) steps. The AGM is only used for 1 − m ≥ MC_ASC = 1e-2, i.e.
#: b0/a0 = k' ≥ 0.1. Then c_i/a_i runs 0.995, 0.82, 0.27, 0.02, 1e-4, 3e-9, 1e-18,
#: 1e-36 (quadratic: c_{i+1} = c_i²/(4 a_{i+1})), so after 7 steps the neglected
#: amplitude term ~ 2^-7 c_8/a_8 is < 1e-38, far below double rounding.
N_AGM = 7
#: Carlson duplication steps. After N steps the relative Taylor-tail error is about
#: ε_N⁶ with ε_N = 4^-N·max|A0 − x_i|/A_N ≤ 4^-N·2·(A0/A_N) [C95], [DLMF 19.36(i)] (each step
#: shrinks it by 4⁶ = 4096). A0/A_N ≈ A0·R² (R the value of the integral) is largest
#: for the tiniest 1 − m handled with a period (MC_SEP: K ≈ 323, A0/A_N ≈ 7e4), which
#: needs 4^N ≥ 7e7. Measured against mpmath (R_F(0, 1−m, 1), R_J(0, 1−m, 1, 1.5)):
#: N = 8 reaches 2e-16 for 1 − m ≥ 1e-16, N = 11 for 1e-100, N = 12 for 1e-280;
#: one step of margin gives 13.
N_CARLSON = 13
#: Below this 1 − m, sn/cn/dn go through two ascending Landen steps plus the
#: hyperbolic approximation instead of the AGM. Reason: on [0, K/2] the AGM's cn, dn
#: come out as cos(φ0) with φ0 near π/2 and lose relative accuracy roughly like
#: ε (1 − m)^-0.4 (measured 3e-15 at 1e-3, 7e-13 at 1e-9, 2e-11 at 3e-12), while the
#: ascending route maps 1 − m ≤ 1e-2 to k3'² ≤ 3e-12 where the corrected hyperbolic
#: formulas are exact to < 3e-16.
MC_ASC = 1e-2
#: Below this 1 − m the motion is treated as exactly on the separatrix (no period;
#: K would exceed ~320 and underflow starts in (1 − m)·sd² ~ 1e-300).
MC_SEP = 1e-280
#: Steady rotation if λ² (scaled: I_max = 1, max|ω_i| = 1) is below this: then
#: |λ h| ≤ 1e-100·h·max|ω_i| and ω changes by less than that relative amount.
LAM2_STEADY = 1e-200

_TINY = 1e-300
_EPS = 2.220446049250313e-16
_PI = math.pi


def _pow2_below(x: ca.SX) -> ca.SX:
    """A power of two within a factor 2 of ``x > 0`` (1e-300 guard for x = 0)."""
    return 2.0 ** ca.floor(ca.log(ca.fmax(x, _TINY)) * (1.0 / math.log(2.0)))


def _sx(v) -> ca.SX:
    return v if isinstance(v, ca.SX) else ca.SX(v)


# --------------------------------------------------------------------------------------
# Carlson symmetric integrals
# --------------------------------------------------------------------------------------
def carlson_rf(x: ca.SX, y: ca.SX, z: ca.SX, n_iter: int = N_CARLSON) -> ca.SX:
    """Carlson's ``R_F(x, y, z) = ½∫₀^∞ dt/√((t+x)(t+y)(t+z))`` (dimensionless if x, y, z are).

    Duplication theorem ``R_F(x,y,z) = R_F((x+λ)/4, (y+λ)/4, (z+λ)/4)`` with
    ``λ = √x√y + √y√z + √z√x`` [DLMF 19.26.18], ``n_iter`` times, then the
    5th-order Taylor tail in the elementary symmetric functions E2, E3 of the
    deviations [DLMF 19.36(i)], [C95]. Needs x, y, z ≥ 0, at most one zero. Each step
    shrinks the deviations by 4 and the tail error (6th order) by 4⁶ = 4096;
    see :data:`N_CARLSON` for the count.
    """
    for _ in range(n_iter):
        sx, sy, sz = ca.sqrt(x), ca.sqrt(y), ca.sqrt(z)
        lam = sx * (sy + sz) + sy * sz
        x, y, z = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam)
    A = ca.fmax((x + y + z) / 3.0, _TINY)
    X = 1.0 - x / A
    Y = 1.0 - y / A
    Z = -(X + Y)
    E2 = X * Y - Z * Z
    E3 = X * Y * Z
    return (1.0 - E2 / 10.0 + E3 / 14.0 + E2 * E2 / 24.0 - 3.0 * E2 * E3 / 44.0) / ca.sqrt(A)


def rc_one(e: ca.SX) -> ca.SX:
    """``R_C(1, 1 + e)`` for ``e > −1``: ``atan(√e)/√e`` (e ≥ 0) or ``atanh(√−e)/√−e`` (e < 0).

    [DLMF 19.2(iv)] in homogeneous form; ``→ 1`` as ``e → 0`` (guarded, no 0/0).
    """
    t = ca.sqrt(ca.fmax(ca.fabs(e), _TINY))
    return ca.if_else(e >= 0, ca.atan(t) / t, ca.atanh(ca.fmin(t, 1.0 - 1e-16)) / t)


def carlson_rj(
    x: ca.SX,
    y: ca.SX,
    z: ca.SX,
    p: ca.SX,
    delta: ca.SX | None = None,
    n_iter: int = N_CARLSON,
    p_dominant: bool = False,
) -> ca.SX:
    """Carlson's ``R_J(x,y,z,p) = (3/2)∫₀^∞ dt/((t+p)√((t+x)(t+y)(t+z)))`` for p > 0.

    Duplication algorithm of [C95] (see also [DLMF 19.36(i)]): with ``d_i = (√p+√x)(√p+√y)(√p+√z)``
    and ``e_i = 4^{-3i} δ/d_i²``, ``δ = (p−x)(p−y)(p−z)``,
    ``R_J = 6 Σ_i 4^{-i} R_C(1, 1+e_i)/d_i + 4^{-N} A_N^{-3/2} T(E2..E5)``.
    ``delta`` may be passed in closed form (our callers do, so that ``p − x`` etc.
    never suffer cancellation). Needs x, y, z ≥ 0 (at most one zero), p > 0.
    With ``p ≥ max(x, y, z)`` (all uses here) every ``e_i ∈ [0, 1)``; the caller may
    then set ``p_dominant=True`` to drop the (never taken) atanh branch of R_C.
    """
    if delta is None:
        delta = (p - x) * (p - y) * (p - z)
    acc = 0.0
    f = 1.0  # 4^{-i}
    g = 1.0  # 4^{-3i}
    for _ in range(n_iter):
        sx, sy, sz, sp = ca.sqrt(x), ca.sqrt(y), ca.sqrt(z), ca.sqrt(p)
        lam = sx * (sy + sz) + sy * sz
        d = (sp + sx) * (sp + sy) * (sp + sz)
        e = g * delta / (d * d)
        if p_dominant:
            t = ca.sqrt(ca.fmax(e, _TINY))
            rc = ca.atan(t) / t
        else:
            rc = rc_one(e)
        acc = acc + f * rc / d
        f *= 0.25
        g *= 1.0 / 64.0
        x, y, z, p = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam), 0.25 * (p + lam)
    A = ca.fmax((x + y + z + 2.0 * p) / 5.0, _TINY)
    X = 1.0 - x / A
    Y = 1.0 - y / A
    Z = 1.0 - z / A
    P = -0.5 * (X + Y + Z)
    E2 = X * Y + X * Z + Y * Z - 3.0 * P * P
    E3 = X * Y * Z + 2.0 * E2 * P + 4.0 * P * P * P
    E4 = (2.0 * X * Y * Z + E2 * P + 3.0 * P * P * P) * P
    E5 = X * Y * Z * P * P
    T = (
        1.0
        - 3.0 * E2 / 14.0
        + E3 / 6.0
        + 9.0 * E2 * E2 / 88.0
        - 3.0 * E4 / 22.0
        - 9.0 * E2 * E3 / 52.0
        + 3.0 * E5 / 26.0
    )
    return 6.0 * acc + f * T / (A * ca.sqrt(A))


# --------------------------------------------------------------------------------------
# Jacobi elliptic functions and complete integrals
# --------------------------------------------------------------------------------------
def _agm_sequence(m: ca.SX, mc: ca.SX, n_iter: int = N_AGM) -> tuple[list, list]:
    """a_i and c_i/a_i (i = 0..N) of the AGM started at (1, k'), c0 = k [DLMF 22.20(ii)]."""
    a, b, c = _sx(1.0), ca.sqrt(mc), ca.sqrt(m)
    a_s, r_s = [a], [c / a]
    for _ in range(n_iter):
        a_new = 0.5 * (a + b)
        b = ca.sqrt(a * b)
        c = c * c / (4.0 * a_new)  # = (a − b)/2 without cancellation
        a = a_new
        a_s.append(a)
        r_s.append(c / a)
    return a_s, r_s


def jacobi_agm(u: ca.SX, m: ca.SX, mc: ca.SX, n_iter: int = N_AGM) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    """``(sn, cn, dn, K)`` of ``u`` for parameter ``m = k²`` by descending Landen (AGM).

    [DLMF 22.20(ii)]: ``φ_N = 2^N a_N u``, ``φ_{i−1} = (φ_i + asin((c_i/a_i) sin φ_i))/2``,
    ``sn = sin φ0``, ``cn = cos φ0``, ``dn = cos φ0 / cos(φ1 − φ0)``; ``K = π/(2 a_N)``.
    ``mc = 1 − m`` is passed separately (full relative accuracy near m = 1). Accurate
    to a few ulp in absolute terms for any u; ``cn`` and ``dn`` lose RELATIVE accuracy
    like ε/cn, so callers fold u to ``[0, K/2]`` (:func:`jacobi_sn_cn_dn`).
    """
    a_s, r_s = _agm_sequence(m, mc, n_iter)
    phi = (2.0**n_iter) * a_s[-1] * u
    phi_prev = phi
    for i in range(n_iter, 0, -1):
        phi_prev = phi
        phi = 0.5 * (phi + ca.asin(r_s[i] * ca.sin(phi)))
    sn, cn = ca.sin(phi), ca.cos(phi)
    dn = cn / ca.cos(phi_prev - phi)
    return sn, cn, dn, _PI / (2.0 * a_s[-1])


def _ascending(m: ca.SX, mce: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX, ca.SX, ca.SX]:
    """Two ascending Landen steps k -> k2 -> k3 [DLMF 22.7.5], cancellation-free.

    ``k2 = 2√k/(1+k)``, ``k2' = (1−k)/(1+k) = (1−m)/(1+k)²``; likewise k3 from k2.
    Returns ``(k2, k2', k3, k3', ln k3', 1 − k3²)``; ``1 − k3² = k3'²`` is ~ (1−m)⁴/4096.
    """
    k = ca.sqrt(m)
    k2p = mce / (1.0 + k) ** 2
    k2 = 2.0 * ca.sqrt(k) / (1.0 + k)
    k3p = k2p * k2p / (1.0 + k2) ** 2
    k3 = 2.0 * ca.sqrt(k2) / (1.0 + k2)
    ln_k3p = 2.0 * (ca.log(mce) - 2.0 * ca.log(1.0 + k)) - 2.0 * ca.log(1.0 + k2)
    return k2, k2p, k3, k3p, ln_k3p, k3p * k3p


def ellip_k(m: ca.SX, mc: ca.SX) -> ca.SX:
    """Complete integral of the first kind ``K(m)`` (m = k² ∈ [0, 1), mc = 1 − m > 0).

    AGM [DLMF 19.8.5] ``K = π/(2 AGM(1, k'))`` for ``mc ≥ MC_ASC``; otherwise two
    ascending Landen steps ``K(k) = K(k3)/((1 + k)(1 + k2))`` [DLMF 19.8(ii)] and, for
    ``k3' ≤ 1e-5``, the logarithmic expansion [A&S 17.3.26]
    ``K(k3) = Λ + k3'²(Λ − 1)/4``, ``Λ = ln(4/k3')`` (neglected term ~k3'⁴Λ < 1e-20).
    ``ln k3'`` is formed from logarithms, so nothing underflows down to ``mc = MC_SEP``.
    """
    mce = ca.fmax(mc, MC_SEP)
    a_s, _ = _agm_sequence(m, mce)
    k2, _, _, _, ln_k3p, mc3 = _ascending(m, mce)
    lam = math.log(4.0) - ln_k3p
    K_asc = (lam + 0.25 * mc3 * (lam - 1.0)) / ((1.0 + ca.sqrt(m)) * (1.0 + k2))
    return ca.if_else(mc < MC_ASC, K_asc, _PI / (2.0 * a_s[-1]))


def _landen_up(S: ca.SX, C: ca.SX, D: ca.SX, k2: ca.SX, k2p: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(sn, cn, dn)(z|k) from (sn, cn, dn)(z/(1 + k2')|k2) [DLMF 22.7.6–22.7.8].

    ``cn`` uses ``dn2² − k2'``, which vanishes only at z = K; for z ≤ K/2 (our fold)
    ``dn2² ≥ √k2' ≫ k2'``, so all three keep full relative accuracy.
    """
    Dg = ca.fmax(D, _TINY)
    den = k2 * k2 * Dg
    return ((1.0 + k2p) * S * C / Dg, (1.0 + k2p) * (D * D - k2p) / den, (1.0 - k2p) * (D * D + k2p) / den)


def _triple_folded(v: ca.SX, m: ca.SX, mce: ca.SX, asc: ca.SX, sep: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(sn, cn, dn)(v|m) for 0 ≤ v ≤ K/2, all three with RELATIVE accuracy ~1e-15.

    ``mc ≥ MC_ASC``: descending Landen / AGM (:func:`jacobi_agm`). Otherwise two
    ascending Landen steps take ``1 − m`` to ``k3'² ≈ (1 − m)⁴/4096 ≤ 3e-12`` and the
    hyperbolic approximation with its first-order correction [A&S 16.15.1–3] is used
    there (relative error measured < 3e-16 for ``k3'² ≤ 1e-10`` on [0, K/2]).
    """
    S_a, C_a, D_a, _ = jacobi_agm(v, m, mce)
    k2, k2p, k3, k3p, _, mc3 = _ascending(m, mce)
    z = v / ((1.0 + k2p) * (1.0 + k3p))
    zc = ca.fmin(ca.fmax(z, 0.0), 350.0)  # beyond, sech underflows; only the m = 1 branch gets there
    th, sh = ca.tanh(zc), ca.sinh(zc)
    se = 1.0 / ca.cosh(zc)
    mq = 0.25 * ca.if_else(sep, 0.0, mc3)
    S3 = th + mq * (th - zc * se * se)  # tanh u + mc/4 (sinh u cosh u − u) sech² u
    C3 = se - mq * th * (sh - zc * se)  # sech u − mc/4 (sinh u cosh u − u) tanh u sech u
    D3 = se + mq * th * (sh + zc * se)  # sech u + mc/4 (sinh u cosh u + u) tanh u sech u
    S2, C2, D2 = _landen_up(S3, C3, D3, k3, k3p)
    S_h, C_h, D_h = _landen_up(S2, C2, D2, k2, k2p)
    return (ca.if_else(asc, S_h, S_a), ca.if_else(asc, C_h, C_a), ca.if_else(asc, D_h, D_a))


def _triple_reduced(rho: ca.SX, m: ca.SX, mce: ca.SX, K: ca.SX, asc: ca.SX, sep: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(sn, cn, dn)(ρ) for |ρ| ≤ K with relative accuracy of cn, dn near ±K.

    Folds ``|ρ| ∈ (K/2, K]`` to ``v = K − |ρ|`` by [DLMF Table 22.4.3]
    ``sn(K − v) = cn v/dn v``, ``cn(K − v) = k' sn v/dn v``, ``dn(K − v) = k'/dn v``.
    """
    u = ca.fabs(rho)
    refl = u > 0.5 * K
    v = ca.if_else(refl, K - u, u)
    S, Cn, Dn = _triple_folded(v, m, mce, asc, sep)
    kp = ca.sqrt(mce)
    Dg = ca.fmax(Dn, _TINY)
    sn = ca.if_else(refl, Cn / Dg, S)
    cn = ca.if_else(refl, kp * S / Dg, Cn)
    dn = ca.if_else(refl, kp / Dg, Dn)
    return ca.sign(rho) * sn, cn, dn


def jacobi_sn_cn_dn(u: ca.SX, m: ca.SX, mc: ca.SX | None = None) -> tuple[ca.SX, ca.SX, ca.SX]:
    """Jacobi ``sn, cn, dn`` of any real ``u`` for ``m ∈ [0, 1]`` (``mc = 1 − m`` if omitted).

    ``u = 2K k + ρ`` with ``k = floor(u/(2K) + ½)``, ``|ρ| ≤ K``; ``sn, cn`` get the
    factor ``(−1)^k`` [DLMF Table 22.4.3]. For ``mc < MC_SEP`` the
    separatrix limit ``tanh, sech, sech`` [DLMF 22.5(ii)] is returned.
    """
    if mc is None:
        mc = 1.0 - m
    mce = ca.fmax(mc, MC_SEP)
    asc = mc < MC_ASC
    sep = mc < MC_SEP
    K = ca.if_else(sep, 1e300, ellip_k(m, mce))
    k = ca.floor(u / (2.0 * K) + 0.5)
    rho = ca.fmin(ca.fmax(u - 2.0 * K * k, -K), K)
    sn, cn, dn = _triple_reduced(rho, m, mce, K, asc, sep)
    sg = 1.0 - 2.0 * (k - 2.0 * ca.floor(0.5 * k))
    se = 1.0 / ca.cosh(ca.fmin(ca.fabs(u), 700.0))
    return (ca.if_else(sep, ca.tanh(u), sg * sn), ca.if_else(sep, se, sg * cn), ca.if_else(sep, se, dn))


def _pi_reduced(n: ca.SX, N: ca.SX, m: ca.SX, sn: ca.SX, cn: ca.SX, dn: ca.SX, swap: ca.SX, beta: ca.SX) -> ca.SX:
    """``Π(n; φ | m)`` for ``|φ| ≤ π/2`` from ``sin φ = sn``, ``cos φ = cn ≥ 0``, ``Δ(φ) = dn``.

    Carlson form [DLMF 19.25(ii)]: ``Π = s R_F(c², d², 1) + (n'/3) s³ R_J(c², d², 1, 1 − n' s²)``
    with ``n' = n`` if ``|n| ≤ 1``, else ``n' = N = m/n`` and the change of parameter
    [DLMF 19.7(iii)] written cancellation-free as
    ``Π(n; φ) = F(φ) − Π(N; φ) + atan2(s √β, c d)/√β``, ``β = (1 − n)(1 − N) = 1 + m − n − N``
    (its R_C term, ``s R_C(c² d², (1 − n s²)(1 − N s²))``, has ``y − x = s² β`` exactly).
    ``δ = (p−x)(p−y)(p−z) = −n'(1−n')(m−n') s⁶`` is passed in closed form.
    """
    ne = ca.if_else(swap, N, n)
    s2 = sn * sn
    x, y = cn * cn, dn * dn
    RF = carlson_rf(x, y, 1.0)
    RJ = carlson_rj(x, y, 1.0, 1.0 - ne * s2, -ne * (1.0 - ne) * (m - ne) * s2 * s2 * s2, p_dominant=True)
    F = sn * RF
    pe = F + (ne / 3.0) * sn * s2 * RJ
    rb = ca.sqrt(beta)
    return ca.if_else(swap, F - pe + ca.atan2(sn * rb, cn * dn) / rb, pe)


def ellip_pi_amplitude(n: ca.SX, m: ca.SX, sn: ca.SX, cn: ca.SX, dn: ca.SX) -> ca.SX:
    """Incomplete ``Π(n; φ|m) = ∫₀^φ dθ/((1 − n sin²θ)√(1 − m sin²θ))``, |φ| ≤ π/2, n ≤ 0.

    ``sn = sin φ``, ``cn = cos φ ≥ 0``, ``dn = √(1 − m sin²φ)``; see :func:`_pi_reduced`.
    """
    N = m / ca.if_else(n < 0, n, -1.0)
    return _pi_reduced(n, N, m, sn, cn, dn, -n > 1.0, 1.0 + m - n - N)


def _pi_complete(n: ca.SX, N: ca.SX, m: ca.SX, mce: ca.SX, K: ca.SX, swap: ca.SX, beta: ca.SX) -> ca.SX:
    """Complete ``Π(n|m) = K + (n'/3) R_J(0, 1 − m, 1, 1 − n')`` [DLMF 19.25(i)], swap as above
    (complete case of [DLMF 19.7(iii)]: ``Π(n) = K − Π(N) + π/(2√β)``)."""
    ne = ca.if_else(swap, N, n)
    RJ = carlson_rj(0.0, mce, 1.0, 1.0 - ne, -ne * (1.0 - ne) * (m - ne), p_dominant=True)
    pe = K + (ne / 3.0) * RJ
    return ca.if_else(swap, K - pe + 0.5 * _PI / ca.sqrt(beta), pe)


def ellip_pi_complete(n: ca.SX, m: ca.SX, mc: ca.SX | None = None) -> ca.SX:
    """Complete integral of the third kind ``Π(n|m)`` for ``n ≤ 0``, ``0 ≤ m < 1``."""
    if mc is None:
        mc = 1.0 - m
    mce = ca.fmax(mc, MC_SEP)
    N = m / ca.if_else(n < 0, n, -1.0)
    return _pi_complete(n, N, m, mce, ellip_k(m, mce), -n > 1.0, 1.0 + m - n - N)


# --------------------------------------------------------------------------------------
# The flow
# --------------------------------------------------------------------------------------
def _quat_mul(p: list, q: list) -> list:
    """Hamilton product p ⊗ q of scalar-first quaternions given as 4-lists
    (modelsrc.quaternion.quat_mul, the model's one quaternion product)."""
    return ca.vertsplit(quat_mul(ca.vertcat(*p), ca.vertcat(*q)))


def _min_rot(l1: ca.SX, l2: ca.SX, l3: ca.SX) -> list:
    """Unit quaternion of the minimal rotation taking unit ``l`` (l3 ≥ 0) to e3 (module §3)."""
    qw = 1.0 + l3
    nrm = ca.sqrt(ca.fmax(qw * qw + l1 * l1 + l2 * l2, _TINY))
    return [qw / nrm, l2 / nrm, -l1 / nrm, _sx(0.0)]


def _pi_increment(
    n_nu: ca.SX, kap: ca.SX, fac: ca.SX, snr: ca.SX, cnr: ca.SX, sn0: ca.SX, cn0: ca.SX, sn1: ca.SX, cn1: ca.SX
) -> ca.SX:
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


def exact_free_flow(q: ca.SX, w: ca.SX, I: Sequence[ca.SX], h: ca.SX) -> tuple[ca.SX, ca.SX]:
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
    q = _sx(q)
    w = _sx(w)
    I = [_sx(I[0]), _sx(I[1]), _sx(I[2])]
    h = _sx(h)

    # ---- §1 scaling (the flow is invariant under I -> I/s, ω -> ω/W, h -> W h) ----
    # s and W are powers of two, so the scaled numbers are EXACT (an exactly
    # representable separatrix state stays exactly on the separatrix, etc.).
    Imax = ca.fmax(I[0], ca.fmax(I[1], I[2]))
    Wmax = ca.fmax(ca.fabs(w[0]), ca.fmax(ca.fabs(w[1]), ca.fabs(w[2])))
    Is = _pow2_below(Imax)
    W = _pow2_below(Wmax)
    Jb = [Ii / Is for Ii in I]
    wb = [w[i] / W for i in range(3)]
    hn = W * h

    # ---- §1 symbolic ranking of the moments (ties broken by index) ----
    def before(j: int, i: int) -> ca.SX:  # does axis j rank below axis i?
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
    Dab = ca.if_else(ca.fabs(tD3 - tD1) <= 4.0 * _EPS * (tD3 + tD1), 0.0, ca.fmax(tD3 - tD1, 0.0))
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
    kap = ca.sqrt(nu) / ca.sqrt(ca.fmax((1.0 + nu) * (m + nu), _TINY))
    fac = ca.sqrt(nu * (1.0 + nu) * (m + nu))
    A1 = ca.sqrt(e3 / (J1 * ag))
    A2 = ca.sqrt(e3 / (J2 * bg))
    A3 = ca.sqrt(e1 / (J3 * ag))
    lam = sig * ca.sqrt(be1g / JJJ)
    C = sig * a / (J1 * J3)
    has3 = e3 > 0
    r3 = ca.sqrt(ca.fmax(e3, _TINY))
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
    snr, cnr, dnr = _triple_reduced(rho, m, mce, Keff, asc, sep)

    # addition theorem [DLMF 22.8.1–22.8.3], denominator 1 − m sn0² snρ² = dn0² + m sn0² cnρ²
    den = ca.fmax(dn0 * dn0 + m * sn0 * sn0 * cnr * cnr, _TINY)
    sn1 = (sn0 * cnr * dnr + snr * cn0 * dn0) / den
    cn1 = (cn0 * cnr - sn0 * snr * dn0 * dnr) / den
    dn1 = (dn0 * dnr - m * sn0 * cn0 * snr * cnr) / den
    # exact separatrix: direct hyperbolic functions at s0 + Δ [DLMF 22.5(ii)]
    s0s = ca.asinh(sn0 / ca.fmax(cn0, _TINY))
    s1s = s0s + Delta
    sech1 = 1.0 / ca.cosh(ca.fmin(ca.fabs(s1s), 700.0))
    sn1 = ca.if_else(sep, ca.tanh(s1s), sn1)
    cn1 = ca.if_else(sep, sech1, cn1)
    dn1 = ca.if_else(sep, sech1, dn1)

    # ---- §3 the two integrals over [s0, s0 + Δ] ----
    Pic = _pi_complete(-nu, Nn, m, mce, K, swap, beta)
    Pir = _pi_reduced(-nu, Nn, m, snr, cnr, dnr, swap, beta)
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
    thd = thd + 2.0 * _PI * ca.logic_and(rho > 0, thd < -0.5 * _PI) - 2.0 * _PI * ca.logic_and(rho < 0, thd > 0.5 * _PI)
    dG = (kr * _PI + thd) / tau
    lamg = ca.if_else(steady, 1.0, lam)
    chi = L * hn / J3 + (C / lamg) * (L * dPi - J3 * A3 * dG)

    # state after the step in the working frame (sn, cn flip sign per half period)
    sg = 1.0 - 2.0 * (kr - 2.0 * ca.floor(0.5 * kr))
    W1, W2, W3 = A1 * sg * cn1, A2 * sg * sn1, A3 * dn1

    # ---- §3 attitude: R(h) = R(0) Pᵀ [P_l(0)ᵀ Rz(χ) P_l(h)] P ----
    Lg = ca.fmax(L, _TINY)
    p0 = _min_rot(J1 * w1 / Lg, J2 * w2 / Lg, J3 * w3 / Lg)
    p1 = _min_rot(J1 * W1 / Lg, J2 * W2 / Lg, J3 * W3 / Lg)
    qz = [ca.cos(0.5 * chi), _sx(0.0), _sx(0.0), ca.sin(0.5 * chi)]
    dl = _quat_mul(_quat_mul([p0[0], -p0[1], -p0[2], -p0[3]], qz), p1)
    dv_body = [sum(P[k][i] * dl[k + 1] for k in range(3)) for i in range(3)]  # Pᵀ δ_vec

    # steady rotation: Δq = exp(ω h/2) in the body frame
    wn = ca.sqrt(wb[0] ** 2 + wb[1] ** 2 + wb[2] ** 2)
    half = 0.5 * wn * hn
    sfac = ca.if_else(wn > 0, ca.sin(half) / ca.fmax(wn, _TINY), 0.0)
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
