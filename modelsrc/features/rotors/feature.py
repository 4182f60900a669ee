"""The rotors (the gyrostat) as one feature: rotor states, motor inputs, axial inertias, their equations and outputs.

A gyrostat is a rigid body carrying axisymmetric rotors that spin about body-fixed axes
(Wittenburg, "Dynamics of Multibody Systems", the gyrostat; Hughes, "Spacecraft Attitude
Dynamics", ch. 3). Conventions (docs/theory.md §8): the scene's inertia I is the whole
body's, rotors included, about the point it turns about; rotor k has the unit axis g_k
(body frame, fixed), the axial inertia J_k, the state Ω_k (rad/s, its rate relative to
the body) and the input u_k (N·m, the motor torque on the rotor about g_k; the body feels
−u_k g_k). With h = Σ J Ω g the rotors' relative momentum (body frame),

    (I − Σ J g gᵀ) ω̇ = τ − ω × (I ω + h) − Σ g u,      J Ω̇ = u − J g·ω̇       (§8.1)

and the total angular momentum is L = I ω + h (body), the kinetic energy
E = ½ ωᵀ I ω + Σ J Ω (g·ω) + ½ Σ J Ω² (§8.2): the rotors contribute h and their energy
to the body's sums (`Assembly.internal_momentum`, `Assembly.internal_energy`) and replace
Euler's equations by the gyrostat's (`gyrostat_rates`).

Each builder adds its symbols, variables and terms to an ``assembly.Assembly``, the
rotors' own symbols to their record (`RotorSymbols`); `FEATURE` declares them
(modelsrc.feature). A scene without rotors gets none of this.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ... import rigid_body as rb
from ...assembly import Assembly, StatePart
from ...feature import AngularAcceleration, Builder, Feature, Outputs, Phase, Reader, ReadStage, SceneRead
from ...methods import RIGID_FLOW_METHODS
from ...nominal_floors import W_FLOOR
from ...scene_data import SceneData
from ...variables import Kind
from .scene_file import (
    check_rotor_input,
    read_rotors,
    rotor_file_inputs,
    rotor_start_keys,
    with_speed_derivatives,
)


@dataclass
class RotorSymbols:
    """The rotors' own symbols, one entry per rotor in scene order: axial inertias J
    (kg·m²) and unit axes g (body, constants); M_inv: the derived (I − Σ J g gᵀ)⁻¹ of the
    torque-mode rotors; rates, torques, inv_J: the torque-mode rotors' states Ω, inputs u
    and derived 1/J; parts: their state parts; speed: every rotor's Ω by name (a state or,
    in speed mode, an input), accel: the speed-mode rotors' input Ω̇ (§8.5); principal: for
    a diagonal I − Σ J g gᵀ, (the gyroscopic coefficients (I_2 − I_3) M⁻¹_1 ... as
    expressions of p, the derived M⁻¹_i), else None (`principal_gyrostat_rates`)."""

    rates: list[ca.SX] = field(default_factory=list)
    parts: list[StatePart] = field(default_factory=list)
    torques: list[ca.SX] = field(default_factory=list)
    inertias: list[ca.SX] = field(default_factory=list)
    axes: list[ca.DM] = field(default_factory=list)
    M_inv: ca.SX | None = None
    inv_J: list[ca.SX] = field(default_factory=list)
    principal: tuple[ca.SX, ca.SX] | None = None
    speed: dict[str, ca.SX] = field(default_factory=dict)
    accel: dict[str, ca.SX] = field(default_factory=dict)


def symbols(a: Assembly) -> RotorSymbols:
    """The rotors' record in the assembly."""
    return a.feature_state("rotors", RotorSymbols)


def add_rotor_states(a: Assembly) -> None:
    """Omega_<name> (rad/s): each torque-mode rotor's rate relative to the body, after the
    other states (a speed-mode rotor's is an input, `add_rotor_inputs`)."""
    rs = symbols(a)
    for name, r in a.scene.rotors.items():
        if r.speed:
            continue
        sym = ca.SX.sym(f"Omega_{name}")
        rs.rates.append(sym)
        rs.speed[name] = sym
        part = StatePart(f"Omega_{name}", sym, rotational=True)  # Ω couples with ω (§8)
        rs.parts.append(part)
        a.state_parts.append(part)
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
    rs = symbols(a)
    for name, r in a.scene.rotors.items():
        if r.speed:
            Om, Om_dot = ca.SX.sym(f"Omega_{name}"), ca.SX.sym(f"Omega_dot_{name}")
            a.input_blocks += [Om, Om_dot]
            rs.speed[name], rs.accel[name] = Om, Om_dot
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
        a.input_blocks.append(sym)
        rs.torques.append(sym)
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
    rs = symbols(a)
    M, M_torque = a.inertia, a.inertia
    for name, r in a.scene.rotors.items():
        J = ca.SX.sym(f"J_{name}")
        a.parameter(J, [f"J_{name}"], [r.J], "kg.m2", [f"axial moment of inertia of rotor {name}"])
        a.checks.append((f"J_{name} must be > 0", J, True))
        rs.inertias.append(J)
        if not r.speed:  # Ω̇ = u (1/J) − g·ω̇: 1/J once per parameter change, not a division per stage
            rs.inv_J.append(a.derive(f"inv_J_{name}", 1 / J))
        g = ca.DM(np.asarray(r.axis, dtype=float))
        rs.axes.append(g)
        M = M - J * (g @ g.T)
        if not r.speed:  # a speed-mode rotor's axial inertia stays in the matrix (§8.5)
            M_torque = M_torque - J * (g @ g.T)
        if r.propeller:  # thrust k_f Ω² g at its position, drag torque −k_m Ω|Ω| g (§8.6)
            Om = rs.speed[name]
            f_body = r.k_f * Om**2 * g
            a.force_body = a.force_body + f_body
            a.torque = (
                a.torque + ca.cross(ca.DM(np.asarray(r.position, dtype=float)), f_body) - r.k_m * Om * ca.fabs(Om) * g
            )
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
        rs.M_inv = ca.diag(inv)
        moments = [a.inertia[i, i] for i in range(3)]
        rs.principal = (rb.principal_coefficients(moments, [1 / Mt[i, i] for i in range(3)]), inv)
    else:
        rs.M_inv = a.derive("rotor_M_inv", ca.densify(ca.inv(Mt)))


def add_rotor_momentum(a: Assembly, total: ca.SX) -> ca.SX:
    """total + h, h = Σ J Ω g (N·m·s, body): the rotors' momentum relative to the body (§8.1)."""
    rs = symbols(a)
    for J, g, name in zip(rs.inertias, rs.axes, a.scene.rotors):
        total = total + J * rs.speed[name] * g
    return total


def add_rotor_energy(a: Assembly, omega: ca.SX, total: ca.SX) -> ca.SX:
    """total + what the rotors add to ½ ωᵀ I ω at the body rate ω (J): Σ J Ω (g·ω) + ½ Σ J Ω²
    (§8.2; with ω relative to the orbit frame, their part of the Jacobi integral, §9.3)."""
    rs = symbols(a)
    for J, g, name in zip(rs.inertias, rs.axes, a.scene.rotors):
        Om = rs.speed[name]  # a state, or a speed-mode rotor's input (§8.5)
        total = total + J * Om * ca.dot(g, omega) + 0.5 * J * Om**2
    return total


def gyrostat_rates(a: Assembly) -> ca.SX:
    """ω̇ (rad/s², body) of the gyrostat (§8.1, §8.5), and Ω̇ (rad/s²) of each torque-mode rotor
    as the rate of its state part:
    ω̇ = (I − Σ_torque J g gᵀ)⁻¹ (τ − ω × (I ω + h) − Σ_torque g u − Σ_speed J Ω̇ g),
    Ω̇ = u / J − g·ω̇ for the torque-mode rotors (the speed-mode ones' Ω̇ is an input)."""
    rs = symbols(a)
    assert rs.M_inv is not None  # add_rotor_parameters made it
    if rs.principal is not None:
        w_dot = principal_gyrostat_rates(a)
    else:
        tau = a.torque
        for term in a.principal_terms:  # a principal tensor with rotors off its axes: the gravity gradient as a torque
            tau = tau + term.torque()
        rhs = minus_rotor_reactions(a, tau - ca.cross(a.omega, a.inertia @ a.omega + a.internal_momentum()))
        w_dot = rs.M_inv @ rhs
    for part, rate in zip(rs.parts, torque_mode_rates(a, w_dot)):
        part.rate = rate
    return w_dot


def _torque_mode_axes(a: Assembly) -> list[ca.DM]:
    """The spin axes g (body) of the torque-mode rotors, in the order of their inputs."""
    return [g for g, r in zip(symbols(a).axes, a.scene.rotors.values()) if not r.speed]


def minus_rotor_reactions(a: Assembly, rhs: ca.SX) -> ca.SX:
    """rhs − Σ_torque g u − Σ_speed J Ω̇ g (N·m, body): the motors' reactions on the body
    (§8.1, §8.5), subtracted term by term in rotor order."""
    rs = symbols(a)
    out: ca.SX = rhs
    for g, u in zip(_torque_mode_axes(a), rs.torques):
        out = out - g * u
    for J, g, name in zip(rs.inertias, rs.axes, a.scene.rotors):
        if name in rs.accel:
            out = out - J * rs.accel[name] * g
    return out


def torque_mode_rates(a: Assembly, w_dot: ca.SX) -> list[ca.SX]:
    """Ω̇ = u / J − g·ω̇ (rad/s²) of each torque-mode rotor (§8.1), 1/J derived once."""
    rs = symbols(a)
    return [u * inv_J - ca.dot(g, w_dot) for g, u, inv_J in zip(_torque_mode_axes(a), rs.torques, rs.inv_J)]


def principal_gyrostat_rates(a: Assembly) -> ca.SX:
    """ω̇ of gyrostat_rates for a diagonal I − Σ J g gᵀ (principal axes, rotors along them), in
    the form of rigid_body.principal_euler_rhs: ω̇_1 = k_1 ω_2 ω_3 + M⁻¹_1 (τ − ω × h − Σ g u −
    Σ J Ω̇ g)_1 − c M⁻¹_1 ω_1 (+ the gravity gradient 3 n² (I_3 − I_2) M⁻¹_1 ĉ_2 ĉ_3), cyclic,
    k_1 = (I_2 − I_3) M⁻¹_1, the coefficients derived once (docs/theory.md §8.1, §9.2)."""
    rs = symbols(a)
    assert rs.principal is not None
    coeff, inv = rs.principal
    rest = minus_rotor_reactions(a, a.torque_without_friction() - ca.cross(a.omega, a.internal_momentum()))
    k = a.derive("rotor_euler_coeff", coeff)
    c = a.friction_coefficient
    damping = None if c is None else a.derive("rotor_friction_rate", c * a.without_derived(inv))
    w_dot = rb.principal_euler_rhs(a.omega, rest, inv, k, damping)
    for term in a.principal_terms:
        w_dot = w_dot + term.acceleration(coeff, "rotor_")
    return w_dot


def rotor_outputs(a: Assembly, w_dot: ca.SX) -> list[tuple[str, ca.SX, str | None, str]]:
    """Per rotor: (name, expression, unit, description) of its absolute rate g·ω + Ω
    (rad/s) and its angular momentum about its axis J (g·ω + Ω) (N·m·s); a speed-mode rotor
    also outputs the motor torque that holds its speed, u = J (Ω̇ + g·ω̇) + k_m Ω|Ω| (N·m, §8.5)."""
    rs = symbols(a)
    out: list[tuple[str, ca.SX, str | None, str]] = []
    for name, J, g in zip(a.scene.rotors, rs.inertias, rs.axes):
        Om = rs.speed[name]
        r = a.scene.rotors[name]
        if r.speed:
            u = J * (rs.accel[name] + ca.dot(g, w_dot)) + r.k_m * Om * ca.fabs(Om)
            out.append((f"u_{name}", u, "N.m", f"motor torque that holds rotor {name} at Omega_{name} (speed mode)"))
        rate = ca.dot(g, a.omega) + Om
        out.append(
            (f"Omega_abs_{name}", rate, "rad/s", f"absolute spin rate of rotor {name} about its axis, g.w + Omega")
        )
        out.append(
            (f"h_{name}", J * rate, "N.m.s", f"angular momentum of rotor {name} about its axis, J (g.w + Omega)")
        )
    return out


def rotor_input_names(scene: SceneData) -> list[str]:
    """The rotors' FMU inputs in value-reference order: u_<name>, or in speed mode Omega_<name>
    and its derivative Omega_dot_<name> (docs/theory.md §8.5)."""
    names: list[str] = []
    for n, r in scene.rotors.items():
        names += [f"Omega_{n}", f"Omega_dot_{n}"] if r.speed else [f"u_{n}"]
    return names


def rotor_nominals(scene: SceneData, out: dict[str, float]) -> None:
    """A rotor's relative rate is measured like ω: its start rate, at least W_FLOOR (rad/s)."""
    for name, r in scene.rotors.items():
        out[f"Omega_{name}"] = max(abs(r.Omega0), W_FLOOR)


def _read(ctx: SceneRead) -> dict[str, Any]:
    return {"rotors": read_rotors(ctx.rd, ctx.features, ctx.initial, ctx.fields["inertia"])}


FEATURE = Feature(
    name="rotors",
    order=60,
    tables={"rotors": None},
    start_keys=rotor_start_keys,
    readers=(Reader(ReadStage.START, 40, _read),),
    file_inputs=lambda fields: rotor_file_inputs(fields["rotors"]),
    check_input=check_rotor_input,
    derived_inputs=with_speed_derivatives,
    # the splittings work on (q, ω) only: their free flows are the rigid body's, not the gyrostat's (§5.3)
    excluded_methods=RIGID_FLOW_METHODS,
    excluded_why="with rotors they are refused: their flows are the rigid body's, without the rotor states",
    excludes_methods=lambda features, fields: bool(fields["rotors"]),
    adds_torque=lambda scene: any(r.propeller for r in scene.rotors.values()),  # thrust moments and drag (§8.6)
    # motors do work: a speed-mode rotor's, or motor torques given as a schedule (§8.2, §8.5)
    does_work=lambda scene: (
        any(r.speed for r in scene.rotors.values()) or any(k.startswith("u_") for k in scene.inputs)
    ),
    blocks_exact_flow=lambda scene: bool(scene.rotors),  # the exact flow is the rigid body's
    input_names=rotor_input_names,
    builders=(
        Builder(Phase.STATES, 20, add_rotor_states),
        Builder(Phase.INPUTS, 40, add_rotor_inputs),
        Builder(Phase.PARAMETERS, 60, add_rotor_parameters),
    ),
    angular_acceleration=AngularAcceleration(replaces=lambda scene: bool(scene.rotors), omega_dot=gyrostat_rates),
    energy=add_rotor_energy,
    momentum=add_rotor_momentum,
    always=Outputs(10, rotor_outputs),
    nominals=rotor_nominals,
)
