"""Feature builder of the central field (``central_gravity``): a free body's own orbit and gravity-gradient torque.

The central body (gravitational parameter μ = G M, m³/s²) sits at the world origin; the
body's centre of mass is at x = x_cm (world). Its potential to second order in
size/|x| (MacCullagh's formula; Hughes, "Spacecraft Attitude Dynamics", ch. 8; Schaub &
Junkins, "Analytical Mechanics of Space Systems", gravity-gradient torque):

    V = −μ m / r − μ/(2 r³) (tr I − 3 r̂ᵀ I_w r̂),   r = |x|, r̂ = x/r, I_w = R I Rᵀ   (§9.7)

The force on the centre of mass is F = −∂V/∂x (CasADi differentiates V, so force and
torque derive from one potential and the total energy E_total = T + V and the total
angular momentum L_total = m x × v + R (I ω + h) are exact invariants of the equations);
the torque about the centre of mass is τ = (3 μ / r³) ρ̂ × (I ρ̂), ρ̂ = Rᵀ r̂ (body frame).
Outputs: r_orbit (m) and L_total (N·m·s, world, about the central body).
"""

from __future__ import annotations

import casadi as ca

from .assembly import Assembly
from .rotors import rotor_momentum
from .variables import Kind, Variable, vector_names


def add_central_gravity(a: Assembly) -> None:
    """The parameter mu (m³/s², > 0), the force −∂V/∂x_cm (N, world) and the torque
    (3μ/r³) ρ̂ × (I ρ̂) (N·m, body) of the central field; a.V becomes V (§9.7)."""
    if not a.scene.has("central_gravity"):
        return
    assert a.pos is not None and a.mass is not None  # add_motion_states, add_translation made them
    mu = ca.SX.sym("mu")
    a.parameter(mu, ["mu"], [a.scene.mu], "m3/s2", ["gravitational parameter G M of the central body at the origin"])
    a.checks.append(("mu must be > 0 (G M of the central body, m^3/s^2)", mu, True))
    V = potential(a.pos, a.rot.T @ a.pos, a.I, a.mass, mu)
    a.V = V
    a.force = a.force - ca.gradient(V, a.pos)
    rho = a.rot.T @ a.pos  # the body-frame position: ρ̂ = ρ / r
    r2 = ca.dot(a.pos, a.pos)
    # τ = (3μ/r³) ρ̂ × (I ρ̂) = 3μ ρ × (I ρ) / r⁵ (§9.7)
    a.tau = a.tau + 3 * mu * ca.cross(rho, a.I @ rho) / (r2 * r2 * ca.sqrt(r2))


def potential(x: ca.SX, rho: ca.SX, I: ca.SX, m: ca.SX, mu: ca.SX) -> ca.SX:
    """V (J) of MacCullagh's formula: −μ m/r − μ/(2 r³) (tr I − 3 ρ̂ᵀ I ρ̂), x the centre of mass
    (m, world, from the central body), ρ = Rᵀ x the same vector in the body frame (ρ̂ᵀ I ρ̂ =
    r̂ᵀ I_w r̂), I about the centre of mass (kg·m², body), m (kg), μ (m³/s²) (§9.7)."""
    r2 = ca.dot(x, x)
    r = ca.sqrt(r2)
    return -mu * m / r - mu / (2 * r2 * r) * (ca.trace(I) - 3 * ca.dot(rho, I @ rho) / r2)


def central_outputs(a: Assembly) -> ca.SX:
    """r_orbit (m) and L_total (N·m·s, world): m x × v + R (I ω + h), the angular momentum
    about the central body, conserved with the rotors' motors idle and no inputs (§9.7);
    their variables are appended to the assembly. Empty without central_gravity."""
    if not a.scene.has("central_gravity"):
        return ca.SX.zeros(0, 1)
    assert a.pos is not None and a.vel is not None and a.mass is not None
    L = a.mass * ca.cross(a.pos, a.vel) + a.R @ (a.I_cm @ a.w + rotor_momentum(a))
    a.variables.append(
        Variable("r_orbit", Kind.OUTPUT, None, "m", "distance of the centre of mass from the central body")
    )
    a.add(
        vector_names("L_total", 3),
        Kind.OUTPUT,
        [None] * 3,
        "N.m.s",
        [
            f"total angular momentum about the central body (orbit m x_cm x v_cm + spin), world axis {i}"
            for i in (1, 2, 3)
        ],
    )
    return ca.vertcat(ca.norm_2(a.pos), L)
