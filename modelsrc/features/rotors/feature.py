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
rotors' own symbols to their record (modes.RotorSymbols); each rotor's mode (modes.py, and
any mode_<name>.py here) adds its inputs and parameters; `FEATURE` declares them
(modelsrc.feature). A scene without rotors gets none of this.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
from typing import Any

import casadi as ca
import numpy as np

from ... import rigid_body as rb
from ...assembly import Assembly, StatePart
from ...feature import AngularAcceleration, Builder, Feature, FeatureDoc, Outputs, Phase, Reader, ReadStage, SceneRead
from ...methods import RIGID_FLOW_METHODS
from ...nominal_floors import W_FLOOR, checked_magnitude
from ...scene_data import SceneData
from ...variables import Kind
from .modes import SPEED_MODE, TORQUE_MODE, RotorMode, symbols
from .scene_file import (
    check_rotor_input,
    read_rotors,
    rotor_file_inputs,
    rotor_start_keys,
    speed_rate_name,
    with_speed_derivatives,
)


def discover_modes() -> dict[str, RotorMode]:
    """The rotor modes: torque and speed, then the MODE of every module mode_<name>.py of
    this folder, in name order."""
    modes = {m.rules.name: m for m in (TORQUE_MODE, SPEED_MODE)}
    package = sys.modules[__package__]
    for info in sorted(pkgutil.iter_modules(package.__path__), key=lambda i: i.name):
        if info.name.startswith("mode_"):
            mode = getattr(importlib.import_module(f"{__package__}.{info.name}"), "MODE", None)
            if not isinstance(mode, RotorMode) or mode.rules.name in modes:
                raise TypeError(f"{__package__}.{info.name} must define MODE, a RotorMode of a new name")
            modes[mode.rules.name] = mode
    return modes


MODES = discover_modes()
RULES = {name: mode.rules for name, mode in MODES.items()}


def add_rotor_states(a: Assembly) -> None:
    """Omega_<name> (rad/s): the rate relative to the body of each rotor whose mode has it as
    a state (torque mode), after the other states (a speed-mode rotor's is an input)."""
    rs = symbols(a)
    for name, r in a.scene.rotors.items():
        if not MODES[r.mode].rules.state:
            continue
        sym = ca.SX.sym(f"Omega_{name}")
        rs.speed[name] = sym
        part = rs.parts[name] = StatePart(f"Omega_{name}", sym, rotational=True)  # Ω couples with ω (§8)
        a.state_parts.append(part)
        a.add(
            [f"Omega_{name}"],
            Kind.STATE,
            [r.Omega0],
            "rad/s",
            [f"spin rate of rotor {name} relative to the body, about its axis g_{name}"],
        )


def add_rotor_inputs(a: Assembly) -> None:
    """Each rotor's inputs, as its mode has them (modes.py): u_<name> (N·m), the motor torque
    on the rotor about its axis, in torque mode; Omega_<name> (rad/s, relative to the body)
    and its derivative Omega_dot_<name> (rad/s²) in speed mode (docs/theory.md §8.5)."""
    for name, r in a.scene.rotors.items():
        MODES[r.mode].add_inputs(a, name, r)


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
        a.positive_parameters.append(f"J_{name}")  # in [1e-100, 1e100] like the mass (model.add_parameter_ranges)
        rs.inertias.append(J)
        mode = MODES[r.mode]
        mode.add_parameters(a, name, r, J)  # torque mode: 1/J, derived once
        g = ca.DM(np.asarray(r.axis, dtype=float))
        rs.axes.append(g)
        M = M - J * (g @ g.T)
        if mode.torque_driven:  # a rotor whose Ω̇ is known keeps its axial inertia in the matrix (§8.5)
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
    for name, rate in zip(_torque_driven(a), torque_mode_rates(a, w_dot)):
        rs.parts[name].rate = rate
    for name, part in rs.parts.items():
        if name in rs.accel:  # a state whose rate its mode knows
            part.rate = rs.accel[name]
    return w_dot


def _torque_driven(a: Assembly) -> list[str]:
    """The names of the torque-driven rotors (torque mode), in scene order."""
    return [n for n, r in a.scene.rotors.items() if MODES[r.mode].torque_driven]


def _torque_mode_axes(a: Assembly) -> list[ca.DM]:
    """The spin axes g (body) of the torque-driven rotors, in the order of their inputs."""
    return [g for g, r in zip(symbols(a).axes, a.scene.rotors.values()) if MODES[r.mode].torque_driven]


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
        motor_torque = MODES[r.mode].motor_torque
        if motor_torque is not None:
            u = J * (rs.accel[name] + ca.dot(g, w_dot)) + r.k_m * Om * ca.fabs(Om)
            out.append((f"u_{name}", u, "N.m", motor_torque(name)))
        rate = ca.dot(g, a.omega) + Om
        out.append(
            (f"Omega_abs_{name}", rate, "rad/s", f"absolute spin rate of rotor {name} about its axis, g.w + Omega")
        )
        out.append(
            (f"h_{name}", J * rate, "N.m.s", f"angular momentum of rotor {name} about its axis, J (g.w + Omega)")
        )
    return out


def rotor_input_names(scene: SceneData) -> list[str]:
    """The rotors' FMU inputs in value-reference order, as their modes have them: u_<name>, or
    in speed mode Omega_<name> and its derivative Omega_dot_<name> (docs/theory.md §8.5)."""
    return [p.format(n) for n, r in scene.rotors.items() for p in MODES[r.mode].fmu_inputs]


def rotor_nominals(scene: SceneData, out: dict[str, float]) -> None:
    """A rotor's relative rate is measured like ω: its start rate, at least W_FLOOR (rad/s),
    overflow-checked like ω's (its square must be finite)."""
    for name, r in scene.rotors.items():
        out[f"Omega_{name}"] = max(checked_magnitude(scene, f"|initial.Omega_{name}|", abs(r.Omega0)), W_FLOOR)


def _read(ctx: SceneRead) -> dict[str, Any]:
    return {"rotors": read_rotors(ctx.rd, ctx.features, ctx.initial, ctx.fields["inertia"], RULES)}


def _doc(scene: SceneData) -> FeatureDoc | None:
    """The gyrostat's equations in place of Euler's (§8.1), speed mode and propellers where used (§8.5, §8.6)."""
    if not scene.rotors:
        return None
    src = "§8.1 (Wittenburg, the gyrostat; Hughes ch. 3)"
    eqs = [("(I − Σ J g gᵀ) ω̇ = τ − ω × (I ω + h) − Σ g u,  h = Σ J Ω g,  I the whole body's (rotors included)", src)]
    if any(not r.speed for r in scene.rotors.values()):
        eqs.append(
            ("J Ω̇ = u − J g·ω̇  (Ω relative to the body; u the motor torque on the rotor, −u g on the body)", src)
        )
    if any(r.speed for r in scene.rotors.values()):
        eqs.append(("speed mode: Ω, Ω̇ inputs, − Σ_speed J Ω̇ g added; output u = J (Ω̇ + g·ω̇) + k_m Ω|Ω|", "§8.5"))
    if any(r.propeller for r in scene.rotors.values()):
        eqs.append(("propeller at r: thrust k_f Ω² g at r (force and moment r × F), drag torque −k_m Ω|Ω| g", "§8.6"))
    names = ", ".join(f"{n} ({r.mode} mode)" for n, r in scene.rotors.items())
    return FeatureDoc(f"rotors (a gyrostat): {names}", tuple(eqs), replaces_euler=True)


FEATURE = Feature(
    name="rotors",
    doc=_doc,
    order=60,
    tables={"rotors": None},
    start_keys=rotor_start_keys,
    readers=(Reader(ReadStage.START, 40, _read),),
    file_inputs=lambda fields: rotor_file_inputs(fields["rotors"], RULES),
    check_input=lambda rd, var, value, fields: check_rotor_input(rd, var, value, fields["rotors"], RULES),
    derived_inputs=lambda inputs, fields: with_speed_derivatives(inputs, fields["rotors"]),
    # a speed-mode rotor's Omega_dot is re-derived from its Omega schedule (§8.5): a run's driver overrides it
    derived_input_names=lambda fields: frozenset(speed_rate_name(n) for n, r in fields["rotors"].items() if r.speed),
    # the splittings work on (q, ω) only: their free flows are the rigid body's, not the gyrostat's (§5.3)
    excluded_methods=RIGID_FLOW_METHODS,
    excluded_why="with rotors they are refused: their flows are the rigid body's, without the rotor states",
    excludes_methods=lambda features, fields: bool(fields["rotors"]),
    adds_torque=lambda scene: any(r.propeller for r in scene.rotors.values()),  # thrust moments and drag (§8.6)
    # motors do work: a speed-mode rotor's, or motor torques given as a schedule (§8.2, §8.5)
    does_work=lambda scene: any(MODES[r.mode].works(n, scene) for n, r in scene.rotors.items()),
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
