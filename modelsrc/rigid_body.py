"""Rigid-body rotational dynamics in CasADi (docs/theory.md §2, §4).

Every physical equation of the model lives here, once; `model.py` assembles them
for a scene and `integrators.py` steps them.
"""
from __future__ import annotations

import casadi as ca


def euler_rhs(I: ca.SX, w: ca.SX, tau: ca.SX) -> ca.SX:
    """Angular acceleration ω̇ (rad/s², body frame) from Euler's equations.

    I ω̇ + ω × (I ω) = τ with the full inertia tensor I (kg·m², body frame, about the
    fixed point or the centre of mass), ω (rad/s, body) and τ (N·m, body)
    (docs/theory.md §2, lecture notes "Euler's equations"). Solved with a symbolic
    3×3 solve, so products of inertia are handled, not only principal moments.
    """
    return ca.solve(I, tau - ca.cross(w, I @ w))


def gravity_torque(R: ca.SX, r_cm: ca.SX, mass: ca.SX, g_world: ca.SX) -> ca.SX:
    """Torque of gravity about a fixed pivot, body frame (N·m).

    τ = r_cm × (Rᵀ m g): the weight m g (world frame) acts at the centre of mass,
    r_cm (m, body frame) from the pivot (docs/theory.md §4.1, heavy top).
    """
    return ca.cross(r_cm, R.T @ (mass * g_world))


def friction_torque(w: ca.SX, c: ca.SX) -> ca.SX:
    """Viscous friction torque −c ω (N·m, body frame), c in N·m·s/rad (docs/theory.md §4.3)."""
    return -c * w


def world_to_body_torque(R: ca.SX, tau_world: ca.SX) -> ca.SX:
    """A torque given in the world frame, expressed in the body frame: Rᵀ τ_w (N·m)."""
    return R.T @ tau_world


def kinetic_energy(I: ca.SX, w: ca.SX) -> ca.SX:
    """Rotational kinetic energy ½ ωᵀ I ω (J), I about the fixed point / centre of mass."""
    return 0.5 * ca.dot(w, I @ w)


def potential_energy(R: ca.SX, r_cm: ca.SX, mass: ca.SX, g_world: ca.SX) -> ca.SX:
    """Gravitational potential −m g·(R r_cm) (J) with the pivot as reference.

    For g = (0, 0, −g) and r_cm = l e3 this is M g l cos θ (lecture notes, heavy top).
    """
    return -mass * ca.dot(g_world, R @ r_cm)


def angular_momentum_body(I: ca.SX, w: ca.SX) -> ca.SX:
    """Angular momentum L = I ω in the body frame (kg·m²/s = N·m·s)."""
    return I @ w
