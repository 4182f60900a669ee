"""Rigid-body dynamics in CasADi: rotation, the centre of mass, points of the body (docs/theory.md §2, §4, §7).

Every physical equation of the model lives here, once; `model.py` and the features
(`modelsrc/features/`) assemble them for a scene and `integrators.py` steps them.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca

from .quaternion import Rotation, quat_mul


def euler_rhs(I: ca.SX, w: ca.SX, tau: ca.SX, I_inv: ca.SX | None = None) -> ca.SX:
    """Angular acceleration ω̇ (rad/s², body frame) from Euler's equations.

    I ω̇ + ω × (I ω) = τ with the full inertia tensor I (kg·m², body frame, about the
    fixed point or the centre of mass), ω (rad/s, body) and τ (N·m, body)
    (docs/theory.md §2, lecture notes "Euler's equations"), so products of inertia are
    handled, not only principal moments: ω̇ = I⁻¹ (τ − ω × Iω) with I⁻¹ (1/(kg·m²)) given
    (the FMU computes it once per parameter change, `model_derived`), else a symbolic
    3×3 solve.
    """
    if I_inv is not None:
        return I_inv @ (tau - ca.cross(w, I @ w))
    return ca.solve(I, tau - ca.cross(w, I @ w))


def principal_euler_rhs(w: ca.SX, tau: ca.SX, inv_moments: ca.SX, coeff: ca.SX, damping: ca.SX | None = None) -> ca.SX:
    """ω̇ (rad/s², body) of Euler's equations on principal axes, in the form a hand-written
    step takes: ω̇_1 = k_1 ω_2 ω_3 + τ_1/I_1 − (c/I_1) ω_1 (cyclic), with k_1 = (I_2 − I_3)/I_1
    (`principal_coefficients`), 1/I and c/I computed once per parameter change (derived
    parameters): two products for the gyroscopic term of each axis instead of four
    (docs/theory.md §2). tau: the torque without friction (N·m, body); damping: c/I (1/s)
    or None without friction."""
    out = []
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        e = coeff[i] * (w[j] * w[k]) + inv_moments[i] * tau[i]
        out.append(e if damping is None else e - damping[i] * w[i])
    return ca.vertcat(*out)


def principal_coefficients(moments: Sequence[ca.SX], inv: Sequence[ca.SX]) -> ca.SX:
    """(I_2 − I_3) M⁻¹_1, (I_3 − I_1) M⁻¹_2, (I_1 − I_2) M⁻¹_3: the gyroscopic coefficients of
    `principal_euler_rhs` from the principal moments I and the inverse diagonal M⁻¹ that
    multiplies the torque (M = I, or I − Σ J g gᵀ with rotors, docs/theory.md §8.1)."""
    return ca.vertcat(*[(moments[(i + 1) % 3] - moments[(i + 2) % 3]) * inv[i] for i in range(3)])


def gravity_torque(R: ca.SX | Rotation, r_cm: ca.SX, mass: ca.SX, g_world: ca.SX) -> ca.SX:
    """Torque of gravity about a fixed pivot, body frame (N·m).

    τ = r_cm × (Rᵀ m g): the weight m g (world frame) acts at the centre of mass,
    r_cm (m, body frame) from the pivot (docs/theory.md §4.1, heavy top).
    """
    return weight_torque(R, r_cm, mass * g_world)


def weight_torque(R: ca.SX | Rotation, r_cm: ca.SX, weight_world: ca.SX) -> ca.SX:
    """τ = r_cm × (Rᵀ W) (N·m, body frame) of a weight W = m g (N, world frame) at the
    centre of mass, r_cm (m, body) from the pivot: `gravity_torque` with W given (the FMU
    computes m g once per parameter change, docs/theory.md §4.1)."""
    return ca.cross(r_cm, R.T @ weight_world)


def friction_torque(w: ca.SX, c: ca.SX) -> ca.SX:
    """Viscous friction torque −c ω (N·m, body frame), c in N·m·s/rad (docs/theory.md §4.3)."""
    return -c * w


def world_to_body_torque(R: ca.SX | Rotation, tau_world: ca.SX) -> ca.SX:
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


# --- exact sub-flows for the splitting method (docs/theory.md §5.3) ---


def axis_rotation_flow(q: ca.SX, L: ca.SX, e: Sequence | ca.SX, I_axis: ca.SX, h: ca.SX) -> tuple[ca.SX, ca.SX]:
    """Exact flow over h of H_e = L_e²/(2 I_e), one term of the free-body energy in
    principal axes (McLachlan 1993; Reich 1994; Touma & Wisdom 1994), about the body axis
    e (a unit vector along one principal axis, I_e its moment).

    L_e = e·L is constant, the body turns about e at rate θ̇ = L_e/I_e: with θ = h L_e/I_e,
    R ← R exp(θ[e]×) (q ← q ⊗ (cos θ/2, sin θ/2 e)) and the body components of L turn
    the other way, L ← L_e e + cos θ (L − L_e e) − sin θ e × L. |L| is exact. For a
    numeric e (a coordinate axis) CasADi drops the zero terms.
    """
    ev = e if isinstance(e, ca.SX) else ca.vertcat(*e)
    Le = ca.dot(ev, L)
    theta = h * Le / I_axis
    c, s = ca.cos(theta), ca.sin(theta)
    dq = ca.vertcat(ca.cos(theta / 2), ca.sin(theta / 2) * ev)
    L_new = Le * ev + c * (L - Le * ev) - s * ca.cross(ev, L)
    return quat_mul(q, dq), L_new


def fixed_axis_order(I_diag: Sequence) -> tuple:
    """The axis order 1-2-3 (the composition 1-2-3-2-1) with the moments I_diag, in the
    form of `sorted_axis_order`."""
    return ((1, 0, 0), (0, 1, 0), (0, 0, 1), I_diag[0], I_diag[1], I_diag[2])


def sorted_axis_order(I_diag: Sequence) -> tuple:
    """(e_a, e_b, e_c, I_a, I_b, I_c): the principal axes ordered by their moments,
    a the smallest, c the largest (ties by axis number), as symbolic one-hot vectors.
    The composition Φ_a(h/2) Φ_b(h/2) Φ_c(h) Φ_b(h/2) Φ_a(h/2) was the most accurate of
    the six orders on 5 of 6 inertias tried (random initial conditions, 10 s), by up to
    3e4 over the worst on a flat plate (docs/theory.md §5.3); the moments are parameters,
    so the FMU ranks them once per parameter change (`model_derived`)."""
    rank = []
    for k in range(3):
        r = 0
        for j in range(3):
            if j != k:
                r = r + (I_diag[j] < I_diag[k] if j > k else I_diag[j] <= I_diag[k])
        rank.append(r)
    axes, moments = [], []
    for slot in range(3):
        pick = [rank[k] == slot for k in range(3)]
        axes.append(tuple(pick[k] for k in range(3)))
        moments.append(sum(pick[k] * I_diag[k] for k in range(3)))
    return (*axes, *moments)


def free_flow_split(q: ca.SX, L: ca.SX, h: ca.SX, order: Sequence | ca.SX) -> tuple[ca.SX, ca.SX]:
    """Second-order symmetric composition of the three axis flows (docs/theory.md §5.3):
    Φ_a(h/2) Φ_b(h/2) Φ_c(h) Φ_b(h/2) Φ_a(h/2), order = (e_a, e_b, e_c, I_a, I_b, I_c)
    (`sorted_axis_order`, or `fixed_axis_order` for 1-2-3-2-1). Exact |L|, bounded energy
    error."""
    e_a, e_b, e_c, I_a, I_b, I_c = order
    for e, I_e, frac in ((e_a, I_a, 0.5), (e_b, I_b, 0.5), (e_c, I_c, 1.0), (e_b, I_b, 0.5), (e_a, I_a, 0.5)):
        q, L = axis_rotation_flow(q, L, e, I_e, frac * h)
    return q, L


def friction_flow(L: ca.SX, I_diag: Sequence, c: ca.SX, h: ca.SX) -> ca.SX:
    """Exact flow of L̇ = −c ω = −c I⁻¹ L in principal axes: L_i ← e^{−c h/I_i} L_i.
    Unconditionally stable for any stiffness c/I."""
    return ca.vertcat(*[L[i] * ca.exp(-c * h / I_diag[i]) for i in range(3)])


def inverse_dynamics_torque(I: ca.SX, w: ca.SX, w_dot: ca.SX) -> ca.SX:
    """Torque (N·m, body frame) that produces a given motion: Euler's equations solved
    for τ, τ = I ω̇ + ω × (I ω) (docs/theory.md §2.1). For a body held at a constant
    rate about a fixed axis (ω̇ = 0 in the body) it is the bearing torque ω × Iω of the
    MIT 2.003J skewed-bar example (docs/theory.md §4.4)."""
    return I @ w_dot + ca.cross(w, I @ w)


def point_velocity(w_world: ca.SX, r_world: ca.SX, v_origin: ca.SX | None = None) -> ca.SX:
    """Velocity (m/s, world) of a body-fixed point at r (m, world) from a body point B
    moving at v_B (m/s, world; None: B fixed): v = v_B + ω × r (MIT 2.003J notation
    handout §3–4, "Relating reference frames"; docs/theory.md §1.4, §7.2)."""
    v = ca.cross(w_world, r_world)
    return v if v_origin is None else v_origin + v


def point_acceleration(w_world: ca.SX, w_dot_world: ca.SX, r_world: ca.SX, a_origin: ca.SX | None = None) -> ca.SX:
    """Acceleration (m/s², world) of a body-fixed point at r (m, world) from a body point
    B accelerating at a_B (m/s², world; None: B fixed): a = a_B + ω̇ × r + ω × (ω × r)
    (MIT 2.003J notation handout §4–5: Eulerian and centripetal terms; docs/theory.md §1.4, §7.2)."""
    a = ca.cross(w_dot_world, r_world) + ca.cross(w_world, ca.cross(w_world, r_world))
    return a if a_origin is None else a_origin + a


# --- the centre of mass and the moving pivot (docs/theory.md §7) ---


def newton_acceleration(force_world: ca.SX, inv_mass: ca.SX) -> ca.SX:
    """Acceleration of the centre of mass (m/s², world): Σ F = M a_C (MIT 2.003J,
    "Linear momentum for rigid bodies"), F the sum of the external forces (N, world),
    a = F·(1/M) with 1/M (1/kg) given (the FMU computes it once per parameter change)."""
    return force_world * inv_mass


def force_moment(r_body: ca.SX, force_body: ca.SX) -> ca.SX:
    """Moment r × F (N·m, body frame) about the centre of mass of a force F (N, body
    frame) applied at the body point r (m, body frame, from the centre of mass)."""
    return ca.cross(r_body, force_body)


def moving_pivot_torque(R: ca.SX | Rotation, r_cm: ca.SX, mass: ca.SX, g_world: ca.SX, a_pivot: ca.SX) -> ca.SX:
    """Torque (N·m, body) in Euler's equations about a pivot B that accelerates at a_B.

    About a moving point B (MIT 2.003J, "Angular momentum for rigid bodies"):
    Σ τ_B = I_B ω̇ + ω × I_B ω + M [d/dt(r_C × v_B) + v_B × v_C], r_C = B -> centre of
    mass. With v_C = v_B + ω × r_C the bracket is r_C × a_B ((ω × r_C) × v_B and
    v_B × (ω × r_C) cancel), so I_B ω̇ + ω × I_B ω = r_C × M g − M r_C × a_B
    = r_C × Rᵀ M (g − a_B): the top in gravity g − a_B (docs/theory.md §7.3)."""
    return gravity_torque(R, r_cm, mass, g_world - a_pivot)


def pivot_force(mass: ca.SX, a_cm: ca.SX, g_world: ca.SX) -> ca.SX:
    """Force (N, world) the pivot supplies: Newton's law for the centre of mass,
    M a_C = F_pivot + M g (torques are couples and add no force) (docs/theory.md §7.3)."""
    return mass * (a_cm - g_world)


def translational_kinetic_energy(mass: ca.SX, v_cm: ca.SX) -> ca.SX:
    """½ M |v_C|² (J), v_C the centre-of-mass velocity (m/s, world). With the rotational
    ½ ωᵀ I_C ω about the centre of mass it is the whole kinetic energy (Marin, "Analytical
    dynamics": T = ½ M Ṙ² + ½ ωᵀ I ω; docs/theory.md §7.1)."""
    return 0.5 * mass * ca.dot(v_cm, v_cm)
