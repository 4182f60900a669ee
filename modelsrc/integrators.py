"""Integrator steps generated from a right-hand side (docs/theory.md §5).

Each step is a CasADi Function (x, u, p, h) -> x_next whose C is generated; the FMU's
C layer only calls it n times per communication step. Inputs u are held constant
over the step (zero-order hold, the co-simulation convention).
"""
from __future__ import annotations

import casadi as ca


def rk4_step(rhs: ca.Function, project: ca.Function) -> ca.Function:
    """Classic 4th-order Runge–Kutta step followed by a projection.

    rhs: (x, u, p) -> ẋ; project: x -> x mapping back onto the manifold (the unit
    quaternion sphere). Projection after each step keeps |q| = 1 to round-off without
    lowering the order (Hairer, Lubich, Wanner, Geometric Numerical Integration, §IV.4).
    """
    nx = rhs.size1_in(0)
    x = ca.SX.sym("x", nx)
    u = ca.SX.sym("u", rhs.size1_in(1))
    p = ca.SX.sym("p", rhs.size1_in(2))
    h = ca.SX.sym("h")
    k1 = rhs(x, u, p)
    k2 = rhs(x + h / 2 * k1, u, p)
    k3 = rhs(x + h / 2 * k2, u, p)
    k4 = rhs(x + h * k3, u, p)
    x_next = project(x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4))
    return ca.Function("model_step", [x, u, p, h], [x_next], ["x", "u", "p", "h"], ["x_next"])
