r"""Heavy symmetric (Lagrange) top: closed-form reference solution.

Setting and units (SI): fixed pivot at the world origin, gravity
``g_world = (0, 0, -g)``, centre of mass at ``l e3`` in the body frame
(``l > 0`` [m], distance from the pivot along the symmetry axis), ``I1 = I2``
the transverse moment ABOUT THE PIVOT and ``I3`` the axial moment [kg m^2],
mass ``M`` [kg], ``g`` [m/s^2]. Orientation by z-x-z Euler angles
``R = Rz(phi) Rx(theta) Rz(psi)`` (body -> world, world z up), so the potential
is ``V = M g l cos(theta)``. Angles in rad, rates in rad/s, time in s.

Constants of motion (Goldstein; u = cos(theta))
-----------------------------------------------
``p_psi = I3 (psi' + phi' u) = I3 w3 = I1 a``,
``p_phi = I1 (1-u^2) phi' + I3 w3 u = I1 b``,
``alpha = 2 E'/I1`` with ``E' = E - I3 w3^2/2 = I1 (theta'^2 + phi'^2 sin^2)/2 + M g l u``,
``beta = 2 M g l / I1``, and ``u'^2 = f(u) = (1-u^2)(alpha - beta u) - (b - a u)^2``.

Roots (the ill-conditioning is treated with exact identities)
--------------------------------------------------------------
``f`` is a cubic with ``f(+-1) = -(b -+ a)^2 <= 0`` and ``f(u0) = sin^2(theta0) theta0'^2 >= 0``,
so its roots are ``-1 <= u1 <= u0 <= u2 <= 1 <= u3``. We never form ``f`` in
powers of ``u``: the cubic is expanded about the initial point, ``x = u - u0``,
``g(x) = beta x^3 + c2 x^2 + c1 x + c0`` with coefficients taken directly from
the initial data,

  c0 = sin^2 theta0 theta0'^2,  c1 = -2 u0 W - beta sin^2 theta0 + 2 a phi0' sin^2 theta0,
  c2 = 2 beta u0 - W - a^2,      W = alpha - beta u0 = theta0'^2 + phi0'^2 sin^2 theta0,

(using ``b - a u0 = phi0' sin^2 theta0`` exactly). If ``theta0' = 0`` then
``c0 = 0`` and ``x = 0`` is factored out analytically; the other two roots come
from the quadratic ``beta x^2 + c2 x + c1`` by the cancellation-free formula.
This covers the sleeping/vertical start, where ``f = (1-u)^2 (beta (1+u) - a^2)``
has the known double root ``u = 1`` (then ``c0 = c1 = 0``: steady, ``u3 =
a^2/beta - 1``). For ``c0 > 0`` the roots ``x1 in [-(1+u0), 0]`` and
``x2 in [0, 1-u0]`` are bracketed (endpoint values ``-(b+-a)^2`` are exact) and
found with Brent's method, ``x3`` by Vieta plus a Newton polish. Distances to
the poles are kept as ``1 - u = 2 sin^2(theta0/2) - x`` and ``1 + u = 2
cos^2(theta0/2) + x``, and ``theta = 2 atan2(sqrt(1-u), sqrt(1+u))``, so small
tilts (1e-4 rad) keep full relative accuracy.

Solution
--------
``u(t) = u1 + (u2 - u1) sn^2(lam t + tau0 | m)`` (evaluated as
``u0 + x1 cn^2 + x2 sn^2``), ``lam^2 = beta (u3 - u1)/4``,
``m = (u2 - u1)/(u3 - u1)``; ``tau0`` from ``sn^2(tau0) = (u0 - u1)/(u2 - u1)``,
negative when ``u'(0) = -sin(theta0) theta0' < 0``. Nutation period ``2 K(m)/lam``.

``phi' = (b - a u)/(1 - u^2) = (b-a)/(2(1-u)) + (b+a)/(2(1+u))`` and
``psi' = I1 a/I3 - u phi' = I1 a/I3 - a - (b-a)/(2(1-u)) + (b+a)/(2(1+u))``.
With ``1 -+ u = (1 -+ u1)(1 - n_-+ sn^2)``, ``n_- = (u2-u1)/(1-u1)``,
``n_+ = -(u2-u1)/(1+u1)``, both are integrated IN CLOSED FORM:
``int dt/(1 -+ u) = Pi(n_-+; am(lam t + tau0) | m) / (lam (1 -+ u1)) + const``,
with the incomplete elliptic integral of the third kind evaluated by Carlson's
R_F/R_J (shared helpers of :mod:`rbcheck.closed_forms.free_asymmetric`). No ODE and no
numerical quadrature is used.

Not covered (``ValueError``): ``M g l <= 0`` or non-positive inertias;
trajectories reaching a pole of the Euler angles (``b = +-a`` with nonzero
nutation, including a start exactly at ``theta0 = 0``/``pi`` with nonzero
transverse rate), where z-x-z angles are singular. Exactly steady motion
(``c0 = c1 = 0``: steady precession, sleeping top, also the unstable
relative equilibria) is returned as the steady solution. Accuracy degrades
(loss ~ 1/(1 - u2) in phi) as the trajectory approaches a pole.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq
from scipy.special import ellipk, ellipkinc

from ..numerics.rotation_np import (
    euler_zxz_rates_to_omega,
    euler_zxz_to_quat,
    matrix_to_euler_zxz,
    omega_to_euler_zxz_rates,
    quat_to_matrix,
)
from .free_asymmetric import ellippi_complete, ellippi_reduced, jacobi_reduced

__all__ = [
    "HeavyTop",
    "TopConstants",
    "TopInit",
    "TopParams",
    "constants",
    "fast_top_nutation_amplitude",
    "fast_top_nutation_frequency",
    "fast_top_precession_rate",
    "init_from_state",
    "nutation_period",
    "omega",
    "quaternion",
    "roots",
    "sleeping_threshold",
    "solve",
]


@dataclass(frozen=True)
class TopParams:
    """Heavy-top parameters: I1 (transverse, about the pivot) and I3 [kg m^2],
    M [kg], g [m/s^2], l [m] (pivot -> centre of mass along +e3)."""

    I1: float
    I3: float
    M: float
    g: float
    l: float


@dataclass(frozen=True)
class TopInit:
    """Initial z-x-z Euler angles [rad] and their rates [rad/s]."""

    theta0: float
    phi0: float
    psi0: float
    theta_dot0: float
    phi_dot0: float
    psi_dot0: float


@dataclass(frozen=True)
class TopConstants:
    """Constants of motion: a = p_psi/I1, b = p_phi/I1 [rad/s], alpha [1/s^2]
    (= 2E'/I1), beta = 2 M g l / I1 [1/s^2], w3 = body spin [rad/s], E = total
    energy [J] (zero potential at the pivot height)."""

    a: float
    b: float
    alpha: float
    beta: float
    w3: float
    E: float


def sleeping_threshold(I1: float, I3: float, M: float, g: float, l: float) -> float:
    """Critical spin ``sqrt(4 M g l I1)/I3`` [rad/s]: the upright (sleeping) top is
    (linearly) stable iff ``|w3|`` exceeds it (``a^2 > 2 beta``). I1 about the pivot."""
    return float(np.sqrt(4.0 * M * g * l * I1) / I3)


def fast_top_nutation_amplitude(I1: float, I3: float, M: float, g: float, l: float, w3: float, theta0: float) -> float:
    """Fast-top nutation amplitude in ``u = cos(theta)`` (``u2 - u1``) for a top
    released with ``theta0' = phi0' = 0``: ``(I1/I3) (2 M g l/(I3 w3^2)) sin^2 theta0``."""
    return float(I1 / I3 * (2.0 * M * g * l / (I3 * w3**2)) * np.sin(theta0) ** 2)


def fast_top_nutation_frequency(I1: float, I3: float, w3: float) -> float:
    """Fast-top nutation angular frequency ``I3 w3 / I1`` [rad/s] (= a)."""
    return float(I3 * w3 / I1)


def fast_top_precession_rate(I3: float, M: float, g: float, l: float, w3: float) -> float:
    """Fast-top mean (slow) precession rate ``M g l / (I3 w3)`` [rad/s]."""
    return float(M * g * l / (I3 * w3))


def init_from_state(q0: ArrayLike, w0: ArrayLike) -> TopInit:
    """Euler-angle initial data from a quaternion (w,x,y,z; body -> world) and the
    BODY angular velocity [rad/s]. ``ValueError`` at ``sin(theta0) == 0`` unless the
    transverse angular velocity is zero (then ``theta' = phi' = 0``, ``psi' = w3``)."""
    R = quat_to_matrix(np.asarray(q0, dtype=float).reshape(4))
    w0 = np.asarray(w0, dtype=float).reshape(3)
    phi, theta, psi = (float(v) for v in matrix_to_euler_zxz(R))
    if np.hypot(R[0, 2], R[1, 2]) == 0.0:
        if w0[0] != 0.0 or w0[1] != 0.0:
            raise ValueError("top exactly vertical with transverse angular velocity: z-x-z Euler rates undefined")
        return TopInit(theta, phi, psi, 0.0, 0.0, float(w0[2]))
    td, pd, sd = omega_to_euler_zxz_rates(theta, psi, w0)
    return TopInit(theta, phi, psi, float(td), float(pd), float(sd))


def constants(params: TopParams, init: TopInit) -> TopConstants:
    """Constants of motion a, b, alpha, beta (see module docstring)."""
    I1, I3, M, g, l = params.I1, params.I3, params.M, params.g, params.l
    th, td, pd, sd = init.theta0, init.theta_dot0, init.phi_dot0, init.psi_dot0
    u0, s2 = np.cos(th), np.sin(th) ** 2
    w3 = sd + pd * u0
    a = I3 * w3 / I1
    b = (I1 * s2 * pd + I3 * w3 * u0) / I1
    beta = 2.0 * M * g * l / I1
    alpha = td**2 + pd**2 * s2 + beta * u0
    E = 0.5 * I1 * (td**2 + pd**2 * s2) + 0.5 * I3 * w3**2 + M * g * l * u0
    return TopConstants(float(a), float(b), float(alpha), float(beta), float(w3), float(E))


class HeavyTop:
    """Precomputed closed-form solution for one parameter set and initial state.

    ``init.theta0`` is first normalised to [0, pi] (equivalent Euler angles;
    ``self.init`` holds the normalised data). Attributes: ``consts``
    (TopConstants), ``u1 <= u2 <= u3`` (roots of f), ``lam`` [1/s], ``m``,
    ``tau0``, ``period`` (nutation period [s], ``inf`` when steady), ``steady``.
    """

    def __init__(self, params: TopParams, init: TopInit):
        p = params
        if not (p.I1 > 0 and p.I3 > 0):
            raise ValueError("I1 and I3 must be positive")
        if not (p.M * p.g * p.l > 0):
            raise ValueError(
                "need M g l > 0 (centre of mass above the pivot along +e3); for M g l = 0 use free_symmetric"
            )
        # normalise theta0 to [0, pi]: Rz(phi) Rx(-th) Rz(psi) = Rz(phi+pi) Rx(th) Rz(psi+pi)
        th = float(init.theta0)
        if not -np.pi <= th <= np.pi:
            th = float(np.mod(th + np.pi, 2.0 * np.pi) - np.pi)
        if th < 0.0:
            init = TopInit(-th, init.phi0 + np.pi, init.psi0 + np.pi, -init.theta_dot0, init.phi_dot0, init.psi_dot0)
        elif th != init.theta0:
            init = TopInit(th, init.phi0, init.psi0, init.theta_dot0, init.phi_dot0, init.psi_dot0)
        self.params, self.init = p, init
        c = self.consts = constants(p, init)
        a, beta = c.a, c.beta
        th = float(init.theta0)
        s2 = np.sin(th) ** 2
        self.u0 = float(np.cos(th))
        self.omu0 = 2.0 * np.sin(0.5 * th) ** 2  # 1 - u0, exact
        self.opu0 = 2.0 * np.cos(0.5 * th) ** 2  # 1 + u0, exact
        self.bmau0 = init.phi_dot0 * s2  # b - a u0, exact
        self.bma = self.bmau0 - a * self.omu0  # b - a
        self.bpa = self.bmau0 + a * self.opu0  # b + a
        W = init.theta_dot0**2 + init.phi_dot0**2 * s2
        c0 = s2 * init.theta_dot0**2
        c1 = -2.0 * self.u0 * W - beta * s2 + 2.0 * a * init.phi_dot0 * s2
        c2 = 2.0 * beta * self.u0 - W - a * a
        self._coef = (beta, c2, c1, c0)
        self.vertical = s2 == 0.0
        self.steady = c0 == 0.0 and c1 == 0.0
        if self.vertical and not self.steady:
            raise ValueError(
                "start exactly at theta0 = 0 or pi with nonzero transverse rate: "
                "the trajectory passes through the Euler-angle pole"
            )
        if self.steady:
            x1 = x2 = 0.0
            x3 = -c2 / beta
        elif c0 == 0.0:
            disc = max(c2 * c2 - 4.0 * beta * c1, 0.0)
            qq = -0.5 * (c2 + np.copysign(np.sqrt(disc), c2))
            r = sorted([0.0, qq / beta, c1 / qq])
            x1, x2, x3 = r
        else:
            x1 = self._bracket_root(-self.opu0, 0.0, -(self.bpa**2), c0)
            x2 = self._bracket_root(0.0, self.omu0, c0, -(self.bma**2))
            x3 = -c2 / beta - x1 - x2
            gp = 3 * beta * x3**2 + 2 * c2 * x3 + c1
            if gp != 0.0:
                x3 -= self._g(x3) / gp
        if not self.steady and x2 > x1 and (self.bma == 0.0 or self.bpa == 0.0):
            raise ValueError(
                "b = +-a: the symmetry axis passes through the vertical, where z-x-z Euler angles are singular"
            )
        self.x1, self.x2, self.x3 = float(x1), float(x2), float(x3)
        self.u1, self.u2, self.u3 = self.u0 + x1, self.u0 + x2, self.u0 + x3
        self.omu1 = self.omu0 - x1  # 1 - u1 (sum of non-negatives)
        self.opu1 = self.opu0 + x1  # 1 + u1
        self.omu2 = self.omu0 - x2  # 1 - u2
        if self.steady:
            self.lam, self.m, self.tau0, self.period = 1.0, 0.0, 0.0, np.inf
            return
        if x3 <= x2:
            raise ValueError("roots not separated (u2 == u3): no periodic closed form")
        self.lam = float(np.sqrt(beta * (x3 - x1) / 4.0))
        d = x2 - x1
        self.m = float(d / (x3 - x1))
        self.period = float(2.0 * ellipk(self.m) / self.lam)
        amp = np.arctan2(np.sqrt(-x1 / d), np.sqrt(x2 / d))  # sn^2(tau0) = -x1/d
        tau0 = float(ellipkinc(amp, self.m))
        if init.theta_dot0 * np.sin(th) > 0.0:  # u'(0) < 0
            tau0 = -tau0
        self.tau0 = tau0
        self.n_minus = d / self.omu1
        self.n_plus = -d / self.opu1
        self.Pc_minus = ellippi_complete(self.n_minus, self.m, p=self.omu2 / self.omu1)
        self.Pc_plus = ellippi_complete(self.n_plus, self.m, p=(self.opu0 + x2) / self.opu1)
        self._P0 = self._pis(np.array([0.0]))

    # -- internals -------------------------------------------------------------
    def _g(self, x):
        b3, c2, c1, c0 = self._coef
        return ((b3 * x + c2) * x + c1) * x + c0

    def _bracket_root(self, lo, hi, glo, ghi):
        if glo == 0.0:
            return lo
        if ghi == 0.0:
            return hi

        def fun(x):
            if x == lo:
                return glo
            if x == hi:
                return ghi
            return self._g(x)

        return brentq(fun, lo, hi, xtol=1e-300, rtol=4.5 * np.finfo(float).eps, maxiter=500)

    def _jac(self, t):
        return jacobi_reduced(self.lam * np.asarray(t, dtype=float) + self.tau0, self.m)

    def _pis(self, t):
        k, _, sn, cn, dn, _ = self._jac(t)
        x = self.x1 * cn**2 + self.x2 * sn**2
        pm = ellippi_reduced(self.n_minus, sn, cn, dn, p=(self.omu0 - x) / self.omu1)
        pp = ellippi_reduced(self.n_plus, sn, cn, dn, p=(self.opu0 + x) / self.opu1)
        return pm + 2 * k * self.Pc_minus, pp + 2 * k * self.Pc_plus

    # -- public ----------------------------------------------------------------
    def x(self, t: ArrayLike) -> NDArray[np.float64]:
        """``u(t) - u0`` (accurate offset from the initial cos(theta))."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if self.steady:
            return np.zeros_like(t)
        _, _, sn, cn, _, _ = self._jac(t)
        return self.x1 * cn**2 + self.x2 * sn**2

    def u(self, t: ArrayLike) -> NDArray[np.float64]:
        """``u(t) = cos(theta(t))``."""
        return self.u0 + self.x(t)

    def angles(self, t: ArrayLike):
        """``(theta, phi, psi)`` [rad] at times ``t`` [s] (phi, psi unwrapped)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        ini, c = self.init, self.consts
        if self.steady:
            th = np.full_like(t, float(ini.theta0))
            if self.vertical:  # R = Rz(phi) Rx(0 or pi) Rz(psi): spin carried by psi
                return th, np.full_like(t, ini.phi0), ini.psi0 + c.w3 * t
            return th, ini.phi0 + ini.phi_dot0 * t, ini.psi0 + ini.psi_dot0 * t
        x = self.x(t)
        theta = 2.0 * np.arctan2(np.sqrt(self.omu0 - x), np.sqrt(self.opu0 + x))
        pm, pp = self._pis(t)
        im = (pm - self._P0[0][0]) / (self.lam * self.omu1)  # int_0^t dt/(1-u)
        ip = (pp - self._P0[1][0]) / (self.lam * self.opu1)  # int_0^t dt/(1+u)
        p = self.params
        phi = ini.phi0 + 0.5 * self.bma * im + 0.5 * self.bpa * ip
        psi = ini.psi0 + (p.I1 * c.a / p.I3 - c.a) * t - 0.5 * self.bma * im + 0.5 * self.bpa * ip
        return theta, phi, psi

    def rates(self, t: ArrayLike):
        """``(theta_dot, phi_dot, psi_dot)`` [rad/s] at times ``t`` [s]."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        ini, c, p = self.init, self.consts, self.params
        if self.steady:
            if self.vertical:
                return np.zeros_like(t), np.zeros_like(t), np.full_like(t, c.w3)
            return (np.zeros_like(t), np.full_like(t, ini.phi_dot0), np.full_like(t, ini.psi_dot0))
        _, _, sn, cn, dn, _ = self._jac(t)
        x = self.x1 * cn**2 + self.x2 * sn**2
        omu, opu = self.omu0 - x, self.opu0 + x
        udot = 2.0 * self.lam * (self.x2 - self.x1) * sn * cn * dn
        sin_th = np.sqrt(omu * opu)
        theta_dot = -udot / sin_th
        phi_dot = (self.bmau0 - c.a * x) / (omu * opu)
        psi_dot = p.I1 * c.a / p.I3 - (self.u0 + x) * phi_dot
        return theta_dot, phi_dot, psi_dot

    def quaternion(self, t: ArrayLike) -> NDArray[np.float64]:
        """Unit quaternions (w,x,y,z), body -> world, shape (n, 4)."""
        theta, phi, psi = self.angles(t)
        return euler_zxz_to_quat(phi, theta, psi)

    def omega(self, t: ArrayLike) -> NDArray[np.float64]:
        """BODY angular velocity [rad/s], shape (n, 3)."""
        theta, _, psi = self.angles(t)
        td, pd, sd = self.rates(t)
        w = euler_zxz_rates_to_omega(theta, psi, td, pd, sd)
        w[..., 2] = self.consts.w3  # exact: w3 is a constant of motion
        return w


def roots(params: TopParams, init: TopInit) -> tuple[float, float, float]:
    """Sorted roots ``u1 <= u2 <= u3`` of ``f(u)`` (``-1 <= u1 <= u2 <= 1 <= u3``)."""
    h = HeavyTop(params, init)
    return h.u1, h.u2, h.u3


def nutation_period(params: TopParams, init: TopInit) -> float:
    """Nutation period ``2 K(m)/lam`` [s] (``inf`` for steady motion)."""
    return HeavyTop(params, init).period


def solve(params: TopParams, init: TopInit, t: ArrayLike):
    """Closed-form z-x-z Euler angles ``(theta, phi, psi)`` [rad] at times ``t`` [s]."""
    return HeavyTop(params, init).angles(t)


def quaternion(params: TopParams, init: TopInit, t: ArrayLike) -> NDArray[np.float64]:
    """Closed-form attitude quaternions (w,x,y,z; body -> world), shape (n, 4)."""
    return HeavyTop(params, init).quaternion(t)


def omega(params: TopParams, init: TopInit, t: ArrayLike) -> NDArray[np.float64]:
    """Closed-form BODY angular velocity [rad/s], shape (n, 3)."""
    return HeavyTop(params, init).omega(t)
