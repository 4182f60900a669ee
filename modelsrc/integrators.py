"""Integrator steps generated from a right-hand side (docs/theory.md §5).

Each step is a CasADi Function (x, u, p, h) -> x_next whose C is generated; the FMU's
C layer only calls it n times per communication step. Inputs u are held constant
over the step (zero-order hold, the co-simulation convention). Every step ends with a
projection back onto the unit-quaternion sphere.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np
from numpy.polynomial import legendre as npleg
from numpy.polynomial import polynomial as nppoly


def _symbols(rhs: ca.Function, kind=ca.SX):
    x = kind.sym("x", rhs.size1_in(0))
    u = kind.sym("u", rhs.size1_in(1))
    p = kind.sym("p", rhs.size1_in(2))
    h = kind.sym("h")
    return x, u, p, h


def explicit_rk_step(
    rhs: ca.Function, project: ca.Function, A: np.ndarray, b: Sequence[float] | np.ndarray, name: str
) -> ca.Function:
    """Explicit Runge–Kutta step of Butcher tableau (A strictly lower triangular, b)."""
    x, u, p, h = _symbols(rhs)
    k: list[ca.SX] = []
    for i in range(len(b)):
        xi = x
        for j in range(i):
            if A[i, j] != 0.0:
                xi = xi + h * float(A[i, j]) * k[j]
        k.append(rhs(xi, u, p))
    x_next = x
    for bi, ki in zip(b, k):
        if bi != 0.0:
            x_next = x_next + h * float(bi) * ki
    return ca.Function(name, [x, u, p, h], [project(x_next), 0], ["x", "u", "p", "h"], ["x_next", "err"])


def rk4_step(rhs: ca.Function, project: ca.Function, name: str = "model_step_rk4") -> ca.Function:
    """Classic 4th-order Runge–Kutta (Hairer–Nørsett–Wanner I, §II.1), then projection.

    Projection after each step keeps |q| = 1 to round-off without lowering the order
    (Hairer, Lubich, Wanner, Geometric Numerical Integration, §IV.4).
    """
    A = np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]], dtype=float)
    return explicit_rk_step(rhs, project, A, [1 / 6, 1 / 3, 1 / 3, 1 / 6], name)


def rk8_step(rhs: ca.Function, project: ca.Function, name: str = "model_step_rk8") -> ca.Function:
    """8th-order explicit Runge–Kutta of Dormand–Prince (DOP853's 12-stage propagator,
    Hairer–Nørsett–Wanner I §II.10), used with a fixed step; tableau from scipy."""
    from scipy.integrate._ivp import dop853_coefficients as dop

    s = dop.N_STAGES
    return explicit_rk_step(rhs, project, np.asarray(dop.A[:s, :s], float), np.asarray(dop.B, float), name)


def gauss_tableau(s: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss–Legendre collocation tableau (A, b, c) with s stages, order 2s.

    Nodes c are the roots of the shifted Legendre polynomial; a_ij = ∫₀^{c_i} ℓ_j,
    b_j = ∫₀¹ ℓ_j with ℓ_j the Lagrange polynomials on c (Hairer–Wanner II §IV.5).
    """
    nodes, _ = npleg.leggauss(s)
    c = (np.sort(nodes) + 1) / 2
    A = np.zeros((s, s))
    b = np.zeros(s)
    for j in range(s):
        others = np.delete(c, j)
        lj = nppoly.polyfromroots(others) / np.prod(c[j] - others)
        Lj = nppoly.polyint(lj)
        b[j] = nppoly.polyval(1.0, Lj)
        A[:, j] = nppoly.polyval(c, Lj)
    return A, b, c


def gauss_step(
    rhs: ca.Function, project: ca.Function, s: int, name: str, newton_tol: float = 1e-14, max_iter: int = 20
) -> ca.Function:
    """Implicit Gauss–Legendre step with s stages (s = 1: implicit midpoint).

    Order 2s, A-stable, symplectic; preserves every quadratic invariant exactly (|q|,
    and |L|² and 2T of the free body) up to the Newton tolerance (Hairer–Lubich–Wanner
    §IV.2). Stage increments Z_i = h Σ_j a_ij f(x + Z_j) are solved with CasADi's
    code-generable `fast_newton` rootfinder (exact Jacobian, ||residual||∞ ≤ newton_tol
    or max_iter iterations); x_next = x + Σ_j d_j Z_j with dᵀ = bᵀA⁻¹, which saves s
    right-hand-side evaluations.
    """
    A, b, c = gauss_tableau(s)
    d = np.linalg.solve(A.T, b)
    nx = rhs.size1_in(0)
    x, u, p, h = _symbols(rhs, ca.MX)
    Z = ca.MX.sym("Z", nx * s)
    Zs = ca.vertsplit(Z, nx)
    F = [rhs(x + Zj, u, p) for Zj in Zs]
    res = ca.vertcat(*[Zs[i] - h * sum(float(A[i, j]) * F[j] for j in range(s)) for i in range(s)])
    G = ca.Function(f"{name}_residual", [Z, x, u, p, h], [res])
    solver = ca.rootfinder(
        f"{name}_newton", "fast_newton", G, {"abstol": newton_tol, "abstolStep": 0.0, "max_iter": max_iter}
    )
    f0 = rhs(x, u, p)
    guess = ca.vertcat(*[float(c[i]) * h * f0 for i in range(s)])  # explicit Euler predictor
    Zvec = solver(guess, x, u, p, h)
    Zsol = ca.vertsplit(Zvec, nx)
    x_next = x + sum(float(d[j]) * Zsol[j] for j in range(s))
    # err: scaled residual left by Newton; the C layer rejects the step above NEWTON_ACCEPT
    err = ca.norm_inf(G(Zvec, x, u, p, h)) / ca.fmax(1, ca.norm_inf(Zvec))
    return ca.Function(name, [x, u, p, h], [project(x_next), err], ["x", "u", "p", "h"], ["x_next", "err"])


def splitting_step(
    project: ca.Function,
    nx: int,
    nu: int,
    np_: int,
    torque,
    I_diag,
    friction_c,
    name: str = "model_step_splitting",
    exact: bool = False,
    accel=None,
) -> ca.Function:
    """Explicit Lie–Poisson splitting (docs/theory.md §5.3), order 2:
    kick(h/2) ∘ damp(h/2) ∘ free flow(h) ∘ damp(h/2) ∘ kick(h/2)
    (Dullweber, Leimkuhler & McLachlan, J. Chem. Phys. 107, 1997). The kick applies the
    torques that depend on the orientation only (gravity, held inputs) exactly:
    L ← L + h τ(q, u). Friction is its exact exponential decay. The free flow is the
    composition of axis rotations (`rigid_body.free_flow_split`), or with exact=True the
    exact torque-free flow (`exact_free_flow`, Celledoni et al. 2008) — then a scene
    without torques is integrated exactly at any step. Needs principal body axes.

    With a moving reference point (states x[7:10] position, x[10:13] velocity, world) the
    kick also gives the velocity h a(q, u) and the free flow drifts the position by h v,
    the exact flows of v̇ = a and ẋ = v (docs/theory.md §7.4): a constant a (uniform
    gravity, world forces, a held pivot acceleration) gives the exact parabola.

    torque(q, u, p) -> τ (body frame, without friction); I_diag(p) -> 3 principal
    moments; friction_c(p) -> c or None; accel(q, u, p) -> a (m/s², world) or None.
    """
    from . import rigid_body as rb
    from .exact_free_flow import exact_free_flow

    x = ca.SX.sym("x", nx)
    u = ca.SX.sym("u", nu)
    p = ca.SX.sym("p", np_)
    h = ca.SX.sym("h")
    Id = I_diag(p)
    c = friction_c(p)
    q, w = x[0:4], x[4:7]
    L = ca.vertcat(*[Id[i] * w[i] for i in range(3)])
    L = L + 0.5 * h * torque(q, u, p)
    if accel is not None:
        pos, vel = x[7:10], x[10:13] + 0.5 * h * accel(q, u, p)  # kick
    if c is not None:
        L = rb.friction_flow(L, Id, c, 0.5 * h)
    if exact:
        q, w_mid = exact_free_flow(q, ca.vertcat(*[L[i] / Id[i] for i in range(3)]), Id, h)
        L = ca.vertcat(*[Id[i] * w_mid[i] for i in range(3)])
    else:
        q, L = rb.free_flow_split(q, L, Id, h)
    if c is not None:
        L = rb.friction_flow(L, Id, c, 0.5 * h)
    L = L + 0.5 * h * torque(q, u, p)
    w_next = ca.vertcat(*[L[i] / Id[i] for i in range(3)])
    x_next = ca.vertcat(q, w_next)
    if accel is not None:
        pos = pos + h * vel  # drift
        x_next = ca.vertcat(x_next, pos, vel + 0.5 * h * accel(q, u, p))  # kick at the new orientation
    return ca.Function(name, [x, u, p, h], [project(x_next), 0], ["x", "u", "p", "h"], ["x_next", "err"])
