"""Feature builders of the rotors (the gyrostat): rotor states, motor-torque inputs, axial inertias and their equations.

A gyrostat is a rigid body carrying axisymmetric rotors that spin about body-fixed axes
(Wittenburg, "Dynamics of Multibody Systems", the gyrostat; Hughes, "Spacecraft Attitude
Dynamics", ch. 3). Conventions (docs/theory.md §8): the scene's inertia I is the whole
body's, rotors included, about the point it turns about; rotor k has the unit axis g_k
(body frame, fixed), the axial inertia J_k, the state Ω_k (rad/s, its rate relative to
the body) and the input u_k (N·m, the motor torque on the rotor about g_k; the body feels
−u_k g_k). With h = Σ J Ω g the rotors' relative momentum (body frame),

    (I − Σ J g gᵀ) ω̇ = τ − ω × (I ω + h) − Σ g u,      J Ω̇ = u − J g·ω̇       (§8.1)

and the total angular momentum is L = I ω + h (body), the kinetic energy
E = ½ ωᵀ I ω + Σ J Ω (g·ω) + ½ Σ J Ω² (§8.2).

Each builder adds its symbols, variables and terms to an ``assembly.Assembly``; the
value-reference order is ``model.BUILDERS``. A scene without rotors gets none of this.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from . import rigid_body as rb
from .assembly import Assembly
from .orbit import gravity_gradient_torque as orbit_torque
from .orbit import principal_gravity_gradient
from .variables import Kind


def add_rotor_states(a: Assembly) -> None:
    """Omega_<name> (rad/s): each torque-mode rotor's rate relative to the body, after the
    other states (a speed-mode rotor's is an input, `add_rotor_inputs`)."""
    for name, r in a.scene.rotors.items():
        if r.speed:
            continue
        sym = ca.SX.sym(f"Omega_{name}")
        a.rotor_rates.append(sym)
        a.rotor_speed[name] = sym
        a.add(
            [f"Omega_{name}"],
            Kind.STATE,
            [r.Omega0],
            "rad/s",
            [f"spin rate of rotor {name} relative to the body, about its axis g_{name}"],
        )


def add_rotor_inputs(a: Assembly) -> None:
    """u_<name> (N·m): the motor torque on each rotor about its axis (positive spins it up;
    the body feels −u g). Start value: the scene's schedule at t = 0 (0 without one).
    A speed-mode rotor instead takes Omega_<name> (rad/s, relative to the body) and its
    derivative Omega_dot_<name> (rad/s², the driver gives the schedule's; docs/theory.md §8.5)."""
    for name, r in a.scene.rotors.items():
        if r.speed:
            Om, Om_dot = ca.SX.sym(f"Omega_{name}"), ca.SX.sym(f"Omega_dot_{name}")
            a.u_parts += [Om, Om_dot]
            a.rotor_speed[name], a.rotor_accel[name] = Om, Om_dot
            start: list[float | None] = [float(a.scene.input_start(f"{v}_{name}")[0]) for v in ("Omega", "Omega_dot")]
            a.add(
                [f"Omega_{name}"],
                Kind.INPUT,
                start[:1],
                "rad/s",
                [f"spin rate of rotor {name} relative to the body, about its axis (speed mode: prescribed)"],
            )
            a.add(
                [f"Omega_dot_{name}"],
                Kind.INPUT,
                start[1:],
                "rad/s2",
                [
                    f"time derivative of Omega_{name} (speed mode; must be the derivative of the Omega_{name} given, "
                    "else angular momentum is not conserved)"
                ],
            )
            continue
        sym = ca.SX.sym(f"u_{name}")
        a.u_parts.append(sym)
        a.rotor_torques.append(sym)
        a.add(
            [f"u_{name}"],
            Kind.INPUT,
            [float(a.scene.input_start(f"u_{name}")[0])],
            "N.m",
            [f"motor torque on rotor {name} about its axis (the body feels -u_{name} along it)"],
        )


def add_rotor_parameters(a: Assembly) -> None:
    """J_<name> (kg·m², > 0): each rotor's axial inertia; the check that I − Σ J g gᵀ stays
    positive definite (Sylvester's leading minors, docs/theory.md §8.1), and the derived
    inverse (I − Σ J g gᵀ)⁻¹ the equations multiply by. Runs after the inertia (and its
    shift to a pivot) is known, as an expression of the parameters."""
    if not a.scene.rotors:
        return
    M, M_torque = a.I, a.I
    for name, r in a.scene.rotors.items():
        J = ca.SX.sym(f"J_{name}")
        a.parameter(J, [f"J_{name}"], [r.J], "kg.m2", [f"axial moment of inertia of rotor {name}"])
        a.checks.append((f"J_{name} must be > 0", J, True))
        a.rotor_inertias.append(J)
        if not r.speed:  # Ω̇ = u (1/J) − g·ω̇: 1/J once per parameter change, not a division per stage
            a.rotor_inv_J.append(a.derive(f"inv_J_{name}", 1 / J))
        g = ca.DM(np.asarray(r.axis, dtype=float))
        a.rotor_axes.append(g)
        M = M - J * (g @ g.T)
        if not r.speed:  # a speed-mode rotor's axial inertia stays in the matrix (§8.5)
            M_torque = M_torque - J * (g @ g.T)
        if r.propeller:  # thrust k_f Ω² g at its position, drag torque −k_m Ω|Ω| g (§8.6)
            Om = a.rotor_speed[name]
            f_body = r.k_f * Om**2 * g
            a.force_body = a.force_body + f_body
            a.tau = a.tau + ca.cross(ca.DM(np.asarray(r.position, dtype=float)), f_body) - r.k_m * Om * ca.fabs(Om) * g
    M = ca.densify(M)
    minors = (M[0, 0], M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0], ca.det(M))
    for k, m in enumerate(minors, 1):
        a.checks.append(
            (
                f"I - sum J g g^T (the inertia without the rotors' axial parts) must be positive definite: its "
                f"leading minor {k} must be > 0 (each J smaller than the body's inertia about the rotor's axis)",
                m,
                True,
            )
        )
    Mt = ca.densify(M_torque)
    if all(Mt[i, j].is_zero() for i in range(3) for j in range(3) if i != j):
        # diagonal (principal axes, rotors along them): 1/M_i, and the rates in the form of
        # rigid_body.principal_euler_rhs (gyrostat_rates)
        inv = a.derive("rotor_M_inv", ca.vertcat(*[1 / Mt[i, i] for i in range(3)]))
        a.rotor_M_inv = ca.diag(inv)
        moments = [a.I[i, i] for i in range(3)]
        a.rotor_principal = (rb.principal_coefficients(moments, [1 / Mt[i, i] for i in range(3)]), inv)
    else:
        a.rotor_M_inv = a.derive("rotor_M_inv", ca.densify(ca.inv(Mt)))


def rotor_momentum(a: Assembly) -> ca.SX:
    """h = Σ J Ω g (N·m·s, body): the rotors' momentum relative to the body (§8.1)."""
    h = ca.SX.zeros(3)
    for J, g, name in zip(a.rotor_inertias, a.rotor_axes, a.scene.rotors):
        h = h + J * a.rotor_speed[name] * g
    return h


def rotor_energy(a: Assembly) -> ca.SX:
    """What the rotors add to ½ ωᵀ I ω (J): Σ J Ω (g·ω) + ½ Σ J Ω² (§8.2)."""
    e = ca.SX(0)
    for J, g, name in zip(a.rotor_inertias, a.rotor_axes, a.scene.rotors):
        Om = a.rotor_speed[name]
        e = e + J * Om * ca.dot(g, a.w) + 0.5 * J * Om**2
    return e


def gyrostat_rates(a: Assembly) -> tuple[ca.SX, ca.SX]:
    """(ω̇ (rad/s², body), Ω̇ (rad/s², one per torque-mode rotor)) of the gyrostat (§8.1, §8.5):
    ω̇ = (I − Σ_torque J g gᵀ)⁻¹ (τ − ω × (I ω + h) − Σ_torque g u − Σ_speed J Ω̇ g),
    Ω̇ = u / J − g·ω̇ for the torque-mode rotors (the speed-mode ones' Ω̇ is an input)."""
    assert a.rotor_M_inv is not None  # add_rotor_parameters made it
    if a.rotor_principal is not None:
        return principal_gyrostat_rates(a)
    tau = a.tau
    if a.nadir is not None:  # a principal tensor with rotors off its axes: the gravity gradient as a torque
        tau = tau + orbit_torque(a, a.nadir)
    rhs = minus_rotor_reactions(a, tau - ca.cross(a.w, a.I @ a.w + rotor_momentum(a)))
    w_dot = a.rotor_M_inv @ rhs
    return w_dot, torque_mode_rates(a, w_dot)


def _torque_mode_axes(a: Assembly) -> list[ca.DM]:
    """The spin axes g (body) of the torque-mode rotors, in the order of a.rotor_torques."""
    return [g for g, r in zip(a.rotor_axes, a.scene.rotors.values()) if not r.speed]


def minus_rotor_reactions(a: Assembly, rhs: ca.SX) -> ca.SX:
    """rhs − Σ_torque g u − Σ_speed J Ω̇ g (N·m, body): the motors' reactions on the body
    (§8.1, §8.5), subtracted term by term in rotor order."""
    out: ca.SX = rhs
    for g, u in zip(_torque_mode_axes(a), a.rotor_torques):
        out = out - g * u
    for J, g, name in zip(a.rotor_inertias, a.rotor_axes, a.scene.rotors):
        if name in a.rotor_accel:
            out = out - J * a.rotor_accel[name] * g
    return out


def torque_mode_rates(a: Assembly, w_dot: ca.SX) -> ca.SX:
    """Ω̇ = u / J − g·ω̇ (rad/s²) of the torque-mode rotors (§8.1), 1/J derived once."""
    Om_dot = [u * inv_J - ca.dot(g, w_dot) for g, u, inv_J in zip(_torque_mode_axes(a), a.rotor_torques,
                                                                  a.rotor_inv_J)]  # fmt: skip
    return ca.vertcat(*Om_dot) if Om_dot else ca.SX.zeros(0, 1)


def principal_gyrostat_rates(a: Assembly) -> tuple[ca.SX, ca.SX]:
    """gyrostat_rates for a diagonal I − Σ J g gᵀ (principal axes, rotors along them), in the
    form of rigid_body.principal_euler_rhs: ω̇_1 = k_1 ω_2 ω_3 + M⁻¹_1 (τ − ω × h − Σ g u −
    Σ J Ω̇ g)_1 − c M⁻¹_1 ω_1 (+ the gravity gradient 3 n² (I_3 − I_2) M⁻¹_1 ĉ_2 ĉ_3), cyclic,
    k_1 = (I_2 − I_3) M⁻¹_1, the coefficients derived once (docs/theory.md §8.1, §9.2)."""
    assert a.rotor_principal is not None
    coeff, inv = a.rotor_principal
    tau = a.tau if a.c is None else ca.substitute(a.tau, a.c, ca.SX(0))
    rest = minus_rotor_reactions(a, tau - ca.cross(a.w, rotor_momentum(a)))
    k = a.derive("rotor_euler_coeff", coeff)
    damping = None if a.c is None else a.derive("rotor_friction_rate", a.c * a.without_derived(inv))
    w_dot = rb.principal_euler_rhs(a.w, rest, inv, k, damping)
    if a.nadir is not None:
        w_dot = w_dot + principal_gravity_gradient(a, coeff, "rotor_gravity_gradient_coeff")
    return w_dot, torque_mode_rates(a, w_dot)


def rotor_outputs(a: Assembly, w_dot: ca.SX) -> list[tuple[str, ca.SX, str, str]]:
    """Per rotor: (name, expression, unit, description) of its absolute rate g·ω + Ω
    (rad/s) and its angular momentum about its axis J (g·ω + Ω) (N·m·s); a speed-mode rotor
    also outputs the motor torque that holds its speed, u = J (Ω̇ + g·ω̇) + k_m Ω|Ω| (N·m, §8.5)."""
    out = []
    for name, J, g in zip(a.scene.rotors, a.rotor_inertias, a.rotor_axes):
        Om = a.rotor_speed[name]
        r = a.scene.rotors[name]
        if r.speed:
            u = J * (a.rotor_accel[name] + ca.dot(g, w_dot)) + r.k_m * Om * ca.fabs(Om)
            out.append((f"u_{name}", u, "N.m", f"motor torque that holds rotor {name} at Omega_{name} (speed mode)"))
        rate = ca.dot(g, a.w) + Om
        out.append(
            (f"Omega_abs_{name}", rate, "rad/s", f"absolute spin rate of rotor {name} about its axis, g.w + Omega")
        )
        out.append(
            (f"h_{name}", J * rate, "N.m.s", f"angular momentum of rotor {name} about its axis, J (g.w + Omega)")
        )
    return out
