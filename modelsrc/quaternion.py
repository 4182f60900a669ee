"""Unit-quaternion algebra in CasADi (docs/theory.md §1).

Convention: q = (w, x, y, z), scalar first, rotating body -> world, i.e.
v_world = R(q) v_body. Euler angles are z-x-z (φ, θ, ψ) with
R = Rz(φ) Rx(θ) Rz(ψ) as in the lecture notes (Goldstein §4.4); they are outputs
only, never states, because they are singular at θ = 0 where a sleeping top lives.
"""

from __future__ import annotations

import casadi as ca
import numpy as np


def quat_mul(p: ca.SX, q: ca.SX) -> ca.SX:
    """Hamilton product p ⊗ q of two quaternions (scalar first)."""
    pw, pv = p[0], p[1:4]
    qw, qv = q[0], q[1:4]
    w = pw * qw - ca.dot(pv, qv)
    v = pw * qv + qw * pv + ca.cross(pv, qv)
    return ca.vertcat(w, v)


def quat_derivative(q: ca.SX, w_body: ca.SX) -> ca.SX:
    """Kinematics q̇ = ½ q ⊗ (0, ω) with ω in the body frame, rad/s (docs/theory.md §1.2),
    as q ⊗ (0, ½ ω): three halvings instead of four, the same numbers (halving is exact)."""
    return quat_mul(q, ca.vertcat(0, 0.5 * w_body))


def rotation_matrix(q: ca.SX) -> ca.SX:
    """Rotation matrix R (body -> world) of the quaternion q, of any nonzero norm.

    R = ((w² − v·v) 1 + 2 v vᵀ + 2 w [v]×) / |q|² (docs/theory.md §1.1): exact for a
    unit q, and the rotation of q/|q| otherwise — a Model Exchange importer's solver
    lets |q| drift, and outputs and torques must still see a rotation. One division,
    no square root: 1/|q|² once, then nine products (not nine divisions).
    """
    return Rotation(q).matrix


class Rotation:
    """R(q) of `rotation_matrix` as an operator: R v = (R̃ v)/|q|² with R̃ = |q|² R, so a
    product with a vector scales three components instead of nine matrix entries (the
    right-hand sides rotate gravity, world torques and forces once or twice per
    evaluation). `.T` is Rᵀ, `.matrix` the 3×3 SX matrix."""

    def __init__(self, q: ca.SX, raw: ca.SX | None = None, inv: ca.SX | None = None) -> None:
        if raw is None or inv is None:
            w, v = q[0], q[1:4]
            raw = (w * w - ca.dot(v, v)) * ca.SX.eye(3) + 2 * (v @ v.T) + 2 * w * ca.skew(v)
            inv = reciprocal(ca.dot(q, q))
        self.q: ca.SX = q
        self.raw: ca.SX = raw
        self.inv: ca.SX = inv

    @property
    def T(self) -> Rotation:
        return Rotation(self.q, self.raw.T, self.inv)

    @property
    def matrix(self) -> ca.SX:
        return self.raw * self.inv

    def __matmul__(self, v: ca.SX) -> ca.SX:
        return (self.raw @ v) * self.inv


def reciprocal(s: ca.SX) -> ca.SX:
    """1/s as one division whose result is reused: CasADi rewrites a·(1/s) as a/s, so
    scaling n numbers by 1/s would cost n divisions (tens of cycles each, several times a
    multiplication: the rotation matrix alone would divide nine times per right-hand side).
    2/(2 s) equals 1/s exactly (doubling is exact in floating point) and is left alone."""
    return 2.0 / (2.0 * s)


def normalized(q: ca.SX) -> ca.SX:
    """q/|q| (any nonzero vector) with one division (`reciprocal`)."""
    return q * reciprocal(ca.norm_2(q))


def euler_zxz(R: ca.SX) -> ca.SX:
    """z-x-z Euler angles (φ, θ, ψ) in rad of a rotation matrix R = Rz(φ) Rx(θ) Rz(ψ).

    θ = atan2(√(R13² + R23²), R33) ∈ [0, π] is accurate near 0 and π (acos is not).
    For sin θ below 1e-12 only φ + ψ (θ ≈ 0) or φ − ψ (θ ≈ π) is defined; then ψ = 0
    and φ carries the whole rotation, so the outputs stay finite (docs/theory.md §1.3).
    """
    s = ca.sqrt(R[0, 2] ** 2 + R[1, 2] ** 2)
    theta = ca.atan2(s, R[2, 2])
    regular = s > 1e-12
    phi = ca.if_else(regular, ca.atan2(R[0, 2], -R[1, 2]), ca.atan2(R[1, 0], R[0, 0]))
    psi = ca.if_else(regular, ca.atan2(R[2, 0], R[2, 1]), 0)
    return ca.vertcat(phi, theta, psi)


def _quat_from_euler_zxz_fun() -> ca.Function:
    a = ca.SX.sym("a", 3)

    def qz(ang: ca.SX) -> ca.SX:
        return ca.vertcat(ca.cos(ang / 2), 0, 0, ca.sin(ang / 2))

    def qx(ang: ca.SX) -> ca.SX:
        return ca.vertcat(ca.cos(ang / 2), ca.sin(ang / 2), 0, 0)

    q = quat_mul(quat_mul(qz(a[0]), qx(a[1])), qz(a[2]))
    return ca.Function("quat_from_euler_zxz", [a], [q])


_QUAT_FROM_EULER = _quat_from_euler_zxz_fun()


def quat_from_euler_zxz(phi: float, theta: float, psi: float) -> np.ndarray:
    """Unit quaternion (scalar first, body -> world) of z-x-z Euler angles in rad."""
    return np.array(_QUAT_FROM_EULER([phi, theta, psi])).ravel()
