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

from .assembly import Assembly
from .variables import Kind


def add_rotor_states(a: Assembly) -> None:
    """Omega_<name> (rad/s): each rotor's rate relative to the body, after the other states."""
    for name, r in a.scene.rotors.items():
        sym = ca.SX.sym(f"Omega_{name}")
        a.rotor_rates.append(sym)
        a.add(
            [f"Omega_{name}"],
            Kind.STATE,
            [r.Omega0],
            "rad/s",
            [f"spin rate of rotor {name} relative to the body, about its axis g_{name}"],
        )


def add_rotor_inputs(a: Assembly) -> None:
    """u_<name> (N·m): the motor torque on each rotor about its axis (positive spins it up;
    the body feels −u g). Start value: the scene's schedule at t = 0 (0 without one)."""
    for name in a.scene.rotors:
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
    M = a.I
    for name, r in a.scene.rotors.items():
        J = ca.SX.sym(f"J_{name}")
        a.parameter(J, [f"J_{name}"], [r.J], "kg.m2", [f"axial moment of inertia of rotor {name}"])
        a.checks.append((f"J_{name} must be > 0", J, True))
        a.rotor_inertias.append(J)
        g = ca.DM(np.asarray(r.axis, dtype=float))
        a.rotor_axes.append(g)
        M = M - J * (g @ g.T)
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
    a.rotor_M_inv = a.derive("rotor_M_inv", ca.densify(ca.inv(M)))


def rotor_momentum(a: Assembly) -> ca.SX:
    """h = Σ J Ω g (N·m·s, body): the rotors' momentum relative to the body (§8.1)."""
    h = ca.SX.zeros(3)
    for J, g, Om in zip(a.rotor_inertias, a.rotor_axes, a.rotor_rates):
        h = h + J * Om * g
    return h


def rotor_energy(a: Assembly) -> ca.SX:
    """What the rotors add to ½ ωᵀ I ω (J): Σ J Ω (g·ω) + ½ Σ J Ω² (§8.2)."""
    e = ca.SX(0)
    for J, g, Om in zip(a.rotor_inertias, a.rotor_axes, a.rotor_rates):
        e = e + J * Om * ca.dot(g, a.w) + 0.5 * J * Om**2
    return e


def gyrostat_rates(a: Assembly) -> tuple[ca.SX, ca.SX]:
    """(ω̇ (rad/s², body), Ω̇ (rad/s², one per rotor)) of the gyrostat (§8.1):
    ω̇ = (I − Σ J g gᵀ)⁻¹ (τ − ω × (I ω + h) − Σ g u), Ω̇ = u / J − g·ω̇."""
    assert a.rotor_M_inv is not None  # add_rotor_parameters made it
    rhs = a.tau - ca.cross(a.w, a.I @ a.w + rotor_momentum(a))
    for g, u in zip(a.rotor_axes, a.rotor_torques):
        rhs = rhs - g * u
    w_dot = a.rotor_M_inv @ rhs
    Om_dot = [u / J - ca.dot(g, w_dot) for J, g, u in zip(a.rotor_inertias, a.rotor_axes, a.rotor_torques)]
    return w_dot, ca.vertcat(*Om_dot)


def rotor_outputs(a: Assembly) -> list[tuple[str, ca.SX, str, str]]:
    """Per rotor: (name, expression, unit, description) of its absolute rate g·ω + Ω
    (rad/s) and its angular momentum about its axis J (g·ω + Ω) (N·m·s)."""
    out = []
    for name, J, g, Om in zip(a.scene.rotors, a.rotor_inertias, a.rotor_axes, a.rotor_rates):
        rate = ca.dot(g, a.w) + Om
        out.append(
            (f"Omega_abs_{name}", rate, "rad/s", f"absolute spin rate of rotor {name} about its axis, g.w + Omega")
        )
        out.append(
            (f"h_{name}", J * rate, "N.m.s", f"angular momentum of rotor {name} about its axis, J (g.w + Omega)")
        )
    return out
