"""Feature builders of the circular orbit: orbit angle, rate n, gravity-gradient torque, outputs relative to LVLH.

Conventions (docs/theory.md §9; Hughes, "Spacecraft Attitude Dynamics", ch. 8): the
centre of mass moves on a circular orbit of rate n (rad/s). The orbit frame LVLH has
x along-track, z to nadir (towards the central body) and y = z × x = −orbit normal;
it turns at ω_o = −n e_y (its own y axis, fixed in inertial space). The world frame
is the inertial frame that coincides with LVLH at t = 0, so at orbit angle θ = n t

    R_wo(θ) = R_y(−θ):   nadir c_w = (−sin θ, 0, cos θ),   orbit normal o_w = (0, −1, 0)    (§9.1)

The state θ (`orbit_angle`, θ̇ = n) makes the right-hand side autonomous (the generated
steps take no time argument). With gravity_gradient the body feels
τ = 3 n² ĉ × (I ĉ), ĉ = Rᵀ c_w the nadir in the body frame (§9.2), and the Jacobi integral
E_J = ½ ω_rᵀ I ω_r − ½ n² ôᵀ I ô + (3/2) n² ĉᵀ I ĉ (ω_r = ω − n ô, ô = Rᵀ o_w; with
rotors their relative terms) is conserved (§9.3).
"""

from __future__ import annotations

import casadi as ca

from .assembly import Assembly
from .quaternion import quat_mul
from .variables import Kind, vector_names


def add_orbit_state(a: Assembly) -> None:
    """orbit_angle θ (rad): the orbit's angle n t from the start (θ̇ = n), the last state."""
    if not a.scene.has("orbit"):
        return
    a.orbit_angle = ca.SX.sym("orbit_angle")
    a.add(["orbit_angle"], Kind.STATE, [0.0], "rad", ["orbit angle n*t travelled since the start (LVLH = world at 0)"])


def add_orbit(a: Assembly) -> None:
    """The parameter n_orbit (rad/s, > 0) and, with gravity_gradient, the torque
    3 n² ĉ × (I ĉ) about the centre of mass (docs/theory.md §9.2)."""
    if a.orbit_angle is None:
        return
    n = ca.SX.sym("n_orbit")
    a.parameter(n, ["n_orbit"], [a.scene.orbit_rate], "rad/s", ["orbit rate n = 2 pi / orbital period (circular)"])
    a.checks.append(("n_orbit must be > 0 (the rate of a circular orbit, rad/s)", n, True))
    a.n_orbit = n
    if a.scene.has("gravity_gradient"):
        c = nadir_body(a)
        if a.I.sparsity().is_diag():  # principal axes: the rates take it with derived coefficients
            a.nadir = c  # (model.principal_rates, rotors.gyrostat_rates)
        else:
            a.tau = a.tau + gravity_gradient_torque(a, c)


def gravity_gradient_torque(a: Assembly, c: ca.SX) -> ca.SX:
    """3 n² ĉ × (I ĉ) (N·m, body), ĉ the nadir in the body frame (docs/theory.md §9.2)."""
    assert a.n_orbit is not None
    return 3 * a.n_orbit**2 * ca.cross(c, a.I @ c)


def principal_gravity_gradient(a: Assembly, coeff: ca.SX, name: str) -> ca.SX:
    """The gravity gradient's angular acceleration on principal axes (rad/s², body), zero
    without it: 3 n² ĉ × (I ĉ) / M_i = −3 n² k_i ĉ_j ĉ_k (i, j, k cyclic) with the Euler
    coefficients k_i = (I_j − I_k)/M_i (`coeff`, expressions of p), −3 n² k derived once
    under `name` (docs/theory.md §9.2; model.principal_rates, rotors.principal_gyrostat_rates)."""
    if a.nadir is None or a.n_orbit is None:
        return ca.SX.zeros(3)
    gg = a.derive(name, -3 * a.n_orbit**2 * coeff)
    c = a.nadir
    return ca.vertcat(*[gg[i] * (c[(i + 1) % 3] * c[(i + 2) % 3]) for i in range(3)])


def nadir_body(a: Assembly) -> ca.SX:
    """ĉ (body frame): the unit vector to nadir, Rᵀ (−sin θ, 0, cos θ) (§9.1)."""
    assert a.orbit_angle is not None
    th = a.orbit_angle
    return a.rot.T @ ca.vertcat(-ca.sin(th), 0, ca.cos(th))


def orbit_normal_body(a: Assembly) -> ca.SX:
    """ô (body frame): the orbit normal −e_y of the world frame, Rᵀ (0, −1, 0) (§9.1)."""
    return a.rot.T @ ca.SX([0.0, -1.0, 0.0])


def roll_pitch_yaw(R: ca.SX) -> ca.SX:
    """(roll φ, pitch θ, yaw ψ) in rad of R = R_z(ψ) R_y(θ) R_x(φ) (body -> LVLH, the 3-2-1
    sequence: yaw about z, then pitch about y, then roll about x; §9.4). θ ∈ [−π/2, π/2]."""
    roll = ca.atan2(R[2, 1], R[2, 2])
    pitch = ca.atan2(-R[2, 0], ca.sqrt(R[2, 1] ** 2 + R[2, 2] ** 2))
    yaw = ca.atan2(R[1, 0], R[0, 0])
    return ca.vertcat(roll, pitch, yaw)


def orbit_outputs(a: Assembly) -> list[tuple[str, ca.SX, str | None, str]]:
    """(name, expression, unit, description) of the outputs relative to the orbit frame
    (§9.4): q_lvlh, rpy_lvlh, w_lvlh, nadir_body and E_jacobi (§9.3)."""
    if a.orbit_angle is None or a.n_orbit is None:
        return []
    th, n = a.orbit_angle, a.n_orbit
    # q_ow = conj(q_wo), q_wo = (cos(θ/2), 0, −sin(θ/2), 0): R_y(−θ)
    q_ow = ca.vertcat(ca.cos(th / 2), 0, ca.sin(th / 2), 0)
    q_lvlh = quat_mul(q_ow, a.q)
    R_wo_T = ca.vertcat(
        ca.horzcat(ca.cos(th), 0, ca.sin(th)), ca.horzcat(0, 1, 0), ca.horzcat(-ca.sin(th), 0, ca.cos(th))
    )
    c, o = nadir_body(a), orbit_normal_body(a)
    w_rel = a.w - n * o
    E = 0.5 * ca.dot(w_rel, a.I @ w_rel) - 0.5 * n**2 * ca.dot(o, a.I @ o)
    for J, g, name in zip(a.rotor_inertias, a.rotor_axes, a.scene.rotors):  # the rotors' relative terms (§9.3)
        Om = a.rotor_speed[name]  # a state, or a speed-mode rotor's input (§8.5)
        E = E + J * Om * ca.dot(g, w_rel) + 0.5 * J * Om**2
    if a.scene.has("gravity_gradient"):
        E = E + 1.5 * n**2 * ca.dot(c, a.I @ c)
    out: list[tuple[str, ca.SX, str | None, str]] = []
    for name, expr, unit, desc in (
        ("q_lvlh", q_lvlh, None, "orientation quaternion body->LVLH, component {} (scalar first)"),
        ("rpy_lvlh", roll_pitch_yaw(R_wo_T @ a.R), "rad", "roll, pitch, yaw (3-2-1) relative to LVLH, angle {}"),
        ("w_lvlh", w_rel, "rad/s", "angular velocity relative to LVLH, body axis {}"),
        ("nadir_body", c, None, "unit vector to nadir, body axis {}"),
    ):
        comps = "wxyz" if name == "q_lvlh" else ("roll", "pitch", "yaw") if name == "rpy_lvlh" else (1, 2, 3)
        for k, (nm, cmp) in enumerate(zip(vector_names(name, expr.shape[0]), comps)):
            out.append((nm, expr[k], unit, desc.format(cmp)))
    out.append(("E_jacobi", E, "J", "Jacobi integral: energy relative to the orbit frame (conserved, §9.3)"))
    return out
