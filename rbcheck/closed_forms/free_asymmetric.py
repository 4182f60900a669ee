r"""Torque-free asymmetric rigid body: closed form with Jacobi elliptic functions.

Frames/units: body frame = principal axes, inertia ``diag(I1, I2, I3)`` [kg m^2]
(any ordering, all distinct); ``w`` = BODY angular velocity [rad/s]; ``q`` = unit
quaternion (w, x, y, z) body -> world; time in s.

Method (own derivation; attitude idea after Celledoni, Fassò, Säfström, Zanna,
SIAM J. Sci. Comput. 30 (2008) 2084-2112)
-----------------------------------------------------------------------------
1. *Axis relabelling.* With ``D = L^2 - 2 E I_mid`` (computed as
   ``sum_i I_i (I_i - I_mid) w_i^2``) the polhode encircles the largest-inertia
   axis if ``D > 0`` and the smallest if ``D < 0``. A signed permutation ``P``
   (a proper rotation, det +1) maps the body frame to a working frame with
   ``J = (J1, J2, J3)``: J3 = the encircled axis, J2 = intermediate axis.
   ``P`` also includes a half turn so that ``w3 > 0`` and ``w1 >= 0`` initially
   (both are symmetries of Euler's equations). So J is either increasing or
   decreasing; the formulas below hold for both orders.
2. *Angular velocity.* ``w1 = A1 cn(s), w2 = A2 sn(s), w3 = A3 dn(s)``,
   ``s = lam t + s0`` with

   A1^2 = (2E J3 - L^2) / (J1 (J3 - J1)),   A2^2 = (2E J3 - L^2) / (J2 (J3 - J2)),
   A3^2 = (L^2 - 2E J1) / (J3 (J3 - J1)),
   m    = (J2 - J1)(2E J3 - L^2) / ((J3 - J2)(L^2 - 2E J1)),
   lam  = sign(J3 - J2) sqrt((J3 - J2)(L^2 - 2E J1) / (J1 J2 J3)),

   (the differences ``2E J3 - L^2`` and ``L^2 - 2E J1`` are evaluated as sums of
   same-sign terms, without cancellation) and ``s0 = F(atan2(w2/A2, w1/A1) | m)``.
   Separatrix (``m`` rounds to 1 or ``|D|`` at rounding level): the hyperbolic
   limit ``sn = tanh, cn = dn = sech`` is used; the intermediate-axis equilibrium
   (``w1 = w3 = 0``) is returned as a steady rotation.
3. *Attitude.* Let ``l = J w / |L|`` and ``P_l(t)`` the minimal rotation taking
   ``l`` to ``e3`` (quaternion ∝ ``(1 + l3, l2, -l1, 0)``; well conditioned since
   ``l3 > 0``). Then ``R(t) = R0' P_l(0)^T Rz(chi(t)) P_l(t)`` where

   chi' = |L| (2E/|L| + w3) / (|L| + J3 w3)
        = |L|/J3 + C (|L| - J3 A3 dn s) / (1 - n sn^2 s),
   C = (J3 - J1)/(J1 J3),   n = -J3 (J2 - J1) / (J1 (J3 - J2))  (< 0, a constant),

   so that ``chi(t) = |L| t / J3 + (C/lam)[|L| (Pi(n; am s|m) - Pi(n; am s0|m))
   - J3 A3 (G(am s) - G(am s0))]`` with ``G(phi) = int_0^phi dx/(1 - n sin^2 x)
   = atan(sqrt(1-n) tan phi)/sqrt(1-n)`` (elementary) and the incomplete
   elliptic integral of the third kind ``Pi`` evaluated with Carlson's symmetric
   integrals (scipy.special.elliprf / elliprj):
   ``Pi(n; phi|m) = sin(phi) R_F(cos^2, 1 - m sin^2, 1)
   + n/3 sin^3(phi) R_J(cos^2, 1 - m sin^2, 1, 1 - n sin^2)`` for
   ``|phi| <= pi/2``, extended by ``Pi(n; phi + k pi) = Pi(n; phi) + 2 k Pi(n|m)``.
   Everything is closed form (no ODE, no numerical quadrature).
4. *Accuracy detail.* Where ``|s| mod 2K`` is near ``K`` the quarter-period
   identities ``sn(K-v) = cd v``, ``cn(K-v) = k' sd v``, ``dn(K-v) = k' nd v`` are
   used, since scipy's ``dn`` loses relative accuracy there when ``m -> 1``
   (near-separatrix motion; measured 3e-7 relative error at 1 - m = 2e-10).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ellipj, ellipk, ellipkinc, elliprf, elliprj

from ..numerics.rotation_np import matrix_to_quat, quat_conj, quat_from_axis_angle, quat_mul, quat_normalize

__all__ = ["ellippi_complete", "ellippi_jacobi", "ellippi_reduced", "jacobi_reduced", "omega", "solve"]

_EPS = np.finfo(float).eps


# ----------------------------------------------------------------------------
# Elliptic helpers (also used by heavy_top)
# ----------------------------------------------------------------------------
def jacobi_reduced(s: ArrayLike, m: float):
    """Reduce ``s`` by the half period ``2K`` and evaluate sn, cn, dn there.

    Returns ``(k, r, sn, cn, dn, K)`` with ``s = 2 K k + r``, ``|r| <= K``,
    ``sn, cn, dn`` evaluated at ``r`` (``sn^2, cn^2, dn^2`` are 2K-periodic, so
    they equal the values at ``s``; ``am(s) = k pi + am(r)``, while
    ``sn(s) = (-1)^k sn(r)``, ``cn(s) = (-1)^k cn(r)``, ``dn(s) = dn(r)``). For ``m == 1``
    (no period) ``k = 0`` and the hyperbolic functions are used.
    """
    s = np.asarray(s, dtype=float)
    if m >= 1.0:
        ch = np.cosh(s)
        return np.zeros_like(s), s, np.tanh(s), 1.0 / ch, 1.0 / ch, np.inf
    K = float(ellipk(m))
    k = np.round(s / (2.0 * K))
    r = s - 2.0 * K * k
    sn, cn, dn, _ = ellipj(r, m)
    # Near |r| = K (cn, dn small when m -> 1) scipy's dn loses relative accuracy;
    # use the quarter-period shift: sn(K - v) = cn v/dn v, cn(K - v) = k' sn v/dn v,
    # dn(K - v) = k'/dn v, with v = K - |r| small and k' = sqrt(1 - m).
    far = np.abs(r) > 0.5 * K
    if np.any(far):
        v = K - np.abs(r[far])
        sv, cv, dv, _ = ellipj(v, m)
        kp = np.sqrt(1.0 - m)
        sn = np.array(sn, dtype=float)
        cn = np.array(cn, dtype=float)
        dn = np.array(dn, dtype=float)
        sn[far] = np.sign(r[far]) * cv / dv
        cn[far] = kp * sv / dv
        dn[far] = kp / dv
    return k, r, sn, cn, dn, K


def ellippi_reduced(n: float, sn, cn, dn, p=None):
    """Incomplete ``Pi(n; am r | m)`` for ``|r| <= K`` from ``sn, cn, dn`` of ``r``.

    Carlson form ``sn R_F(cn^2, dn^2, 1) + n/3 sn^3 R_J(cn^2, dn^2, 1, p)`` with
    ``p = 1 - n sn^2`` (pass ``p`` if it can be computed more accurately).
    ``Pi(n; phi|m) = int_0^phi dx / ((1 - n sin^2 x) sqrt(1 - m sin^2 x))``; n < 1.
    """
    sn = np.asarray(sn, dtype=float)
    c2 = np.asarray(cn, dtype=float) ** 2
    d2 = np.asarray(dn, dtype=float) ** 2
    if p is None:
        p = 1.0 - n * sn * sn
    out = sn * elliprf(c2, d2, 1.0)
    if n != 0.0:
        out = out + (n / 3.0) * sn**3 * elliprj(c2, d2, 1.0, p)
    return out


def ellippi_complete(n: float, m: float, p: float | None = None) -> float:
    """Complete ``Pi(n|m) = R_F(0, 1-m, 1) + n/3 R_J(0, 1-m, 1, p)``, ``p = 1 - n``."""
    if p is None:
        p = 1.0 - n
    out = float(elliprf(0.0, 1.0 - m, 1.0))
    if n != 0.0:
        out += n / 3.0 * float(elliprj(0.0, 1.0 - m, 1.0, p))
    return out


def ellippi_jacobi(n: float, s: ArrayLike, m: float) -> NDArray[np.float64]:
    """``int_0^s du / (1 - n sn^2(u|m))`` = ``Pi(n; am s | m)`` for any real s (n < 1)."""
    k, _, sn, cn, dn, K = jacobi_reduced(s, m)
    out = ellippi_reduced(n, sn, cn, dn)
    if np.isfinite(K):
        out = out + 2.0 * k * ellippi_complete(n, m)
    return out


def _g_amp(n: float, k, sn, cn):
    """``G(am s) = int_0^{am s} dx/(1 - n sin^2 x)`` from reduced sn, cn (n < 1)."""
    rt = np.sqrt(1.0 - n)
    return (k * np.pi + np.arctan2(rt * sn, cn)) / rt


# ----------------------------------------------------------------------------
# Working frame
# ----------------------------------------------------------------------------
class _Setup:
    """Constants of the motion in the relabelled working frame."""

    def __init__(self, I, w0):
        I = np.asarray(I, dtype=float).reshape(3)
        w0 = np.asarray(w0, dtype=float).reshape(3)
        if np.any(I <= 0.0):
            raise ValueError("principal moments must be positive")
        srt = np.sort(I)
        if np.min(np.diff(srt)) <= 1e-12 * srt[-1]:
            raise ValueError("principal moments must be distinct; use free_symmetric for I1 = I2")
        imin, imid, imax = np.argsort(I)
        terms = I * (I - I[imid]) * w0**2
        D = float(np.sum(terms))  # L^2 - 2 E I_mid
        D_err = 8.0 * _EPS * float(np.sum(np.abs(terms)))
        self.separatrix = abs(D) <= D_err
        a = imin if (D < 0.0 and not self.separatrix) else imax
        b = imax if a == imin else imin
        P = np.zeros((3, 3))
        P[0, b] = 1.0
        P[1, imid] = 1.0
        P[2, a] = 1.0
        if np.linalg.det(P) < 0.0:
            P[0] *= -1.0
        w = P @ w0
        if w[2] < 0.0:  # half turn about axis 1
            P = np.diag([1.0, -1.0, -1.0]) @ P
            w = P @ w0
        if w[0] < 0.0:  # half turn about axis 3
            P = np.diag([-1.0, -1.0, 1.0]) @ P
            w = P @ w0
        J = np.abs(P) @ I
        J1, J2, J3 = J
        self.P, self.J, self.w = P, J, w
        self.L = float(np.linalg.norm(J * w))
        self.twoE = float(np.sum(J * w * w))
        # same-sign sums (no cancellation):
        e3 = J1 * (J3 - J1) * w[0] ** 2 + J2 * (J3 - J2) * w[1] ** 2  # 2E J3 - L^2
        e1 = J2 * (J2 - J1) * w[1] ** 2 + J3 * (J3 - J1) * w[2] ** 2  # L^2 - 2E J1
        self.A1 = np.sqrt(max(e3 / (J1 * (J3 - J1)), 0.0))
        self.A2 = np.sqrt(max(e3 / (J2 * (J3 - J2)), 0.0))
        self.A3 = np.sqrt(max(e1 / (J3 * (J3 - J1)), 0.0))
        self.lam = np.sign(J3 - J2) * np.sqrt(max((J3 - J2) * e1 / (J1 * J2 * J3), 0.0))
        m = (J2 - J1) * e3 / ((J3 - J2) * e1) if e1 != 0.0 else 0.0
        if self.separatrix or m >= 1.0:
            self.separatrix = True
            m = 1.0
        self.m = max(m, 0.0)
        self.equilibrium_mid = self.separatrix and w[0] == 0.0 and w[2] == 0.0
        c1 = w[0] / self.A1 if self.A1 > 0.0 else 1.0
        s1 = w[1] / self.A2 if self.A2 > 0.0 else 0.0
        if self.equilibrium_mid:
            self.s0 = 0.0
        elif self.m >= 1.0:
            c3 = w[2] / self.A3
            self.s0 = float(np.arcsinh(s1 / (0.5 * (c1 + c3))))
        else:
            self.s0 = float(ellipkinc(np.arctan2(s1, c1), self.m))
        self.n = -J3 * (J2 - J1) / (J1 * (J3 - J2))
        self.C = (J3 - J1) / (J1 * J3)


def _omega_work(st: _Setup, t):
    s = st.lam * t + st.s0
    k, _, sn, cn, dn, K = jacobi_reduced(s, st.m)
    sgn = 1.0 - 2.0 * np.mod(k, 2.0)  # sn, cn change sign per half period 2K
    w = np.stack([st.A1 * sgn * cn, st.A2 * sgn * sn, st.A3 * dn], axis=-1)
    return w, s, k, sn, cn, dn, K


def omega(I: ArrayLike, w0: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
    """Body angular velocity [rad/s] at times ``t`` [s], shape (n, 3) (see :func:`solve`)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    st = _Setup(I, w0)
    if st.L == 0.0 or st.equilibrium_mid:
        return np.tile(np.asarray(w0, dtype=float).reshape(3), (t.size, 1))
    w, *_ = _omega_work(st, t)
    return w @ st.P  # P^T w for each row


def _min_rot_quat(l):
    """Quaternion of the minimal rotation taking unit ``l`` (l3 > -1) to e3."""
    q = np.stack([1.0 + l[..., 2], l[..., 1], -l[..., 0], np.zeros_like(l[..., 0])], axis=-1)
    return quat_normalize(q)


def solve(I: ArrayLike, w0: ArrayLike, q0: ArrayLike, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Closed-form torque-free motion of an asymmetric rigid body.

    Parameters
    ----------
    I : principal moments (I1, I2, I3) [kg m^2], positive and distinct, in ANY
        order (the axes are permuted internally by a proper signed permutation
        and the result is mapped back to the caller's body frame).
    w0 : initial body angular velocity [rad/s], shape (3,).
    q0 : initial unit quaternion (w, x, y, z), body -> world (normalised here).
    t : times [s] from the initial state, shape (n,).

    Returns
    -------
    w : (n, 3) body angular velocity [rad/s].
    q : (n, 4) unit quaternions body -> world (w >= 0).

    Covers both polhode families (``L^2 > 2 E I_mid`` and ``< 2 E I_mid``) and
    the separatrix (hyperbolic limit). Raises ``ValueError`` for non-positive or
    (nearly, rel. 1e-12) equal moments.
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    w0 = np.asarray(w0, dtype=float).reshape(3)
    q0 = quat_normalize(np.asarray(q0, dtype=float).reshape(4))
    st = _Setup(I, w0)
    if st.L == 0.0:
        return np.zeros((t.size, 3)), np.tile(q0, (t.size, 1))
    if st.equilibrium_mid:
        q = quat_mul(q0, quat_from_axis_angle(w0 / np.linalg.norm(w0), np.linalg.norm(w0) * t))
        return np.tile(w0, (t.size, 1)), q * np.where(q[:, :1] < 0, -1.0, 1.0)

    w, _s, k, sn, cn, dn, K = _omega_work(st, t)
    k0, _, sn0, cn0, dn0, _ = jacobi_reduced(np.array([st.s0]), st.m)
    n, L, J3, A3 = st.n, st.L, st.J[2], st.A3
    Pi = ellippi_reduced(n, sn, cn, dn)
    Pi0 = ellippi_reduced(n, sn0, cn0, dn0)[0]
    if np.isfinite(K):
        Pc = ellippi_complete(n, st.m)
        Pi = Pi + 2.0 * k * Pc
        Pi0 = Pi0 + 2.0 * k0[0] * Pc
    G = _g_amp(n, k, sn, cn)
    G0 = _g_amp(n, k0, sn0, cn0)[0]
    chi = L * t / J3 + (st.C / st.lam) * (L * (Pi - Pi0) - J3 * A3 * (G - G0))

    # attitude in the working frame: R'(t) = R0' P_l(0)^T Rz(chi) P_l(t)
    qP = matrix_to_quat(st.P)  # v_work = P v_body
    q0w = quat_mul(q0, quat_conj(qP))  # R0' = R0 P^T
    l = (st.J * w) / L
    l0 = (st.J * st.w) / L
    ql = _min_rot_quat(l)
    ql0 = _min_rot_quat(l0)
    qz = quat_from_axis_angle(np.array([0.0, 0.0, 1.0]), chi)
    q = quat_mul(quat_mul(quat_mul(q0w, quat_conj(ql0)), qz), ql)
    q = quat_mul(q, qP)  # back to the caller's body frame
    q = q * np.where(q[:, :1] < 0, -1.0, 1.0)
    return w @ st.P, q
