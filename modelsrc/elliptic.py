"""Elliptic integrals and Jacobi elliptic functions as code-generable CasADi SX graphs, for the exact free flow.

Carlson's symmetric integrals R_F, R_J [C95], [DLMF 19.36]; the AGM / descending
Landen sequence and ascending Landen steps for sn, cn, dn [DLMF 22.20], [A&S 16.15];
complete and incomplete integrals of the first and third kind. Fixed iteration counts
(no loops on data), so every function is one straight-line SX graph whose C CasADi
generates. The derivations and references are in modelsrc/exact_free_flow.py's
docstring; the accuracy is measured in tests/test_exact_free_flow.py.
"""

from __future__ import annotations

import math
from typing import Any, TypeAlias

import casadi as ca

# A CasADi SX expression or a float: these functions build one straight-line graph from
# either (CasADi's type stubs call a mixed if_else/fmax a DM, so a precise type does not fit).
Expr: TypeAlias = Any

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

TINY = 1e-300
EPS = 2.220446049250313e-16
PI = math.pi


def pow2_below(x: Expr) -> Expr:
    """A power of two within a factor 2 of ``x > 0`` (1e-300 guard for x = 0)."""
    return 2.0 ** ca.floor(ca.log(ca.fmax(x, TINY)) * (1.0 / math.log(2.0)))


def as_sx(v: Expr | float) -> Expr:
    """v as a CasADi SX (unchanged if it is one already)."""
    return v if isinstance(v, ca.SX) else ca.SX(v)


# --------------------------------------------------------------------------------------
# Carlson symmetric integrals
# --------------------------------------------------------------------------------------
def carlson_rf(x: Expr, y: Expr, z: Expr, n_iter: int = N_CARLSON) -> Expr:
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
    A = ca.fmax((x + y + z) / 3.0, TINY)
    X = 1.0 - x / A
    Y = 1.0 - y / A
    Z = -(X + Y)
    E2 = X * Y - Z * Z
    E3 = X * Y * Z
    return (1.0 - E2 / 10.0 + E3 / 14.0 + E2 * E2 / 24.0 - 3.0 * E2 * E3 / 44.0) / ca.sqrt(A)


def rc_one(e: Expr) -> Expr:
    """``R_C(1, 1 + e)`` for ``e > −1``: ``atan(√e)/√e`` (e ≥ 0) or ``atanh(√−e)/√−e`` (e < 0).

    [DLMF 19.2(iv)] in homogeneous form; ``→ 1`` as ``e → 0`` (guarded, no 0/0).
    """
    t = ca.sqrt(ca.fmax(ca.fabs(e), TINY))
    return ca.if_else(e >= 0, ca.atan(t) / t, ca.atanh(ca.fmin(t, 1.0 - 1e-16)) / t)


def carlson_rj(
    x: Expr,
    y: Expr,
    z: Expr,
    p: Expr,
    delta: Expr | None = None,
    n_iter: int = N_CARLSON,
    p_dominant: bool = False,
) -> Expr:
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
            t = ca.sqrt(ca.fmax(e, TINY))
            rc = ca.atan(t) / t
        else:
            rc = rc_one(e)
        acc = acc + f * rc / d
        f *= 0.25
        g *= 1.0 / 64.0
        x, y, z, p = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam), 0.25 * (p + lam)
    A = ca.fmax((x + y + z + 2.0 * p) / 5.0, TINY)
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
def _agm_sequence(m: Expr, mc: Expr, n_iter: int = N_AGM) -> tuple[list, list]:
    """a_i and c_i/a_i (i = 0..N) of the AGM started at (1, k'), c0 = k [DLMF 22.20(ii)]."""
    a, b, c = as_sx(1.0), ca.sqrt(mc), ca.sqrt(m)
    a_s, r_s = [a], [c / a]
    for _ in range(n_iter):
        a_new = 0.5 * (a + b)
        b = ca.sqrt(a * b)
        c = c * c / (4.0 * a_new)  # = (a − b)/2 without cancellation
        a = a_new
        a_s.append(a)
        r_s.append(c / a)
    return a_s, r_s


def jacobi_agm(u: Expr, m: Expr, mc: Expr, n_iter: int = N_AGM) -> tuple[Expr, Expr, Expr, Expr]:
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
    return sn, cn, dn, PI / (2.0 * a_s[-1])


def _ascending(m: Expr, mce: Expr) -> tuple[Expr, Expr, Expr, Expr, Expr, Expr]:
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


def ellip_k(m: Expr, mc: Expr) -> Expr:
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
    return ca.if_else(mc < MC_ASC, K_asc, PI / (2.0 * a_s[-1]))


def _landen_up(S: Expr, C: Expr, D: Expr, k2: Expr, k2p: Expr) -> tuple[Expr, Expr, Expr]:
    """(sn, cn, dn)(z|k) from (sn, cn, dn)(z/(1 + k2')|k2) [DLMF 22.7.6–22.7.8].

    ``cn`` uses ``dn2² − k2'``, which vanishes only at z = K; for z ≤ K/2 (our fold)
    ``dn2² ≥ √k2' ≫ k2'``, so all three keep full relative accuracy.
    """
    Dg = ca.fmax(D, TINY)
    den = k2 * k2 * Dg
    return ((1.0 + k2p) * S * C / Dg, (1.0 + k2p) * (D * D - k2p) / den, (1.0 - k2p) * (D * D + k2p) / den)


def _triple_folded(v: Expr, m: Expr, mce: Expr, asc: Expr, sep: Expr) -> tuple[Expr, Expr, Expr]:
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


def triple_reduced(rho: Expr, m: Expr, mce: Expr, K: Expr, asc: Expr, sep: Expr) -> tuple[Expr, Expr, Expr]:
    """(sn, cn, dn)(ρ) for |ρ| ≤ K with relative accuracy of cn, dn near ±K.

    Folds ``|ρ| ∈ (K/2, K]`` to ``v = K − |ρ|`` by [DLMF Table 22.4.3]
    ``sn(K − v) = cn v/dn v``, ``cn(K − v) = k' sn v/dn v``, ``dn(K − v) = k'/dn v``.
    """
    u = ca.fabs(rho)
    refl = u > 0.5 * K
    v = ca.if_else(refl, K - u, u)
    S, Cn, Dn = _triple_folded(v, m, mce, asc, sep)
    kp = ca.sqrt(mce)
    Dg = ca.fmax(Dn, TINY)
    sn = ca.if_else(refl, Cn / Dg, S)
    cn = ca.if_else(refl, kp * S / Dg, Cn)
    dn = ca.if_else(refl, kp / Dg, Dn)
    return ca.sign(rho) * sn, cn, dn


def jacobi_sn_cn_dn(u: Expr, m: Expr, mc: Expr | None = None) -> tuple[Expr, Expr, Expr]:
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
    sn, cn, dn = triple_reduced(rho, m, mce, K, asc, sep)
    sg = 1.0 - 2.0 * (k - 2.0 * ca.floor(0.5 * k))
    se = 1.0 / ca.cosh(ca.fmin(ca.fabs(u), 700.0))
    return (ca.if_else(sep, ca.tanh(u), sg * sn), ca.if_else(sep, se, sg * cn), ca.if_else(sep, se, dn))


def pi_reduced(n: Expr, N: Expr, m: Expr, sn: Expr, cn: Expr, dn: Expr, swap: Expr, beta: Expr) -> Expr:
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


def ellip_pi_amplitude(n: Expr, m: Expr, sn: Expr, cn: Expr, dn: Expr) -> Expr:
    """Incomplete ``Π(n; φ|m) = ∫₀^φ dθ/((1 − n sin²θ)√(1 − m sin²θ))``, |φ| ≤ π/2, n ≤ 0.

    ``sn = sin φ``, ``cn = cos φ ≥ 0``, ``dn = √(1 − m sin²φ)``; see :func:`pi_reduced`.
    """
    N = m / ca.if_else(n < 0, n, -1.0)
    return pi_reduced(n, N, m, sn, cn, dn, -n > 1.0, 1.0 + m - n - N)


def pi_complete(n: Expr, N: Expr, m: Expr, mce: Expr, K: Expr, swap: Expr, beta: Expr) -> Expr:
    """Complete ``Π(n|m) = K + (n'/3) R_J(0, 1 − m, 1, 1 − n')`` [DLMF 19.25(i)], swap as above
    (complete case of [DLMF 19.7(iii)]: ``Π(n) = K − Π(N) + π/(2√β)``)."""
    ne = ca.if_else(swap, N, n)
    RJ = carlson_rj(0.0, mce, 1.0, 1.0 - ne, -ne * (1.0 - ne) * (m - ne), p_dominant=True)
    pe = K + (ne / 3.0) * RJ
    return ca.if_else(swap, K - pe + 0.5 * PI / ca.sqrt(beta), pe)


def ellip_pi_complete(n: Expr, m: Expr, mc: Expr | None = None) -> Expr:
    """Complete integral of the third kind ``Π(n|m)`` for ``n ≤ 0``, ``0 ≤ m < 1``."""
    if mc is None:
        mc = 1.0 - m
    mce = ca.fmax(mc, MC_SEP)
    N = m / ca.if_else(n < 0, n, -1.0)
    return pi_complete(n, N, m, mce, ellip_k(m, mce), -n > 1.0, 1.0 + m - n - N)
