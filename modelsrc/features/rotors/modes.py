"""The rotors' modes (docs/theory.md §8.5): what each takes as input, adds as parameters, and how its rate Ω̇ is known.

A mode is a `RotorMode`: its scene-file rules (`scene_file.ModeRules`) and its part of
the equations. A torque-driven mode (torque) has the motor torque u as its input and its
Ω̇ = u/J − g·ω̇ follows from the body's equation (§8.1); every other mode knows Ω̇ (an input
in speed mode, a law in another) and the body feels −J Ω̇ g, its axial inertia staying in
I − Σ J g gᵀ (§8.5). Here are the built-in torque and speed modes and the rotors' own
record (`RotorSymbols`) the modes fill; a module ``mode_<name>.py`` of this folder that
defines ``MODE`` adds a mode (feature.py finds it).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import casadi as ca

from ...assembly import Assembly, StatePart
from ...scene_data import SceneData
from ...variables import Kind
from .scene_file import SPEED, TORQUE, ModeRules, Rotor


@dataclass
class RotorSymbols:
    """The rotors' own symbols, one entry per rotor in scene order: axial inertias J
    (kg·m²) and unit axes g (body, constants); M_inv: the derived (I − Σ J g gᵀ)⁻¹ of the
    torque-driven rotors; torques, inv_J: the torque-driven rotors' inputs u and derived
    1/J; parts: the state part of each rotor whose rate is a state, by name; speed: every
    rotor's Ω by name (a state or an input), accel: Ω̇ by name of the rotors that know it
    (an input in speed mode, §8.5); principal: for a diagonal I − Σ J g gᵀ, (the gyroscopic
    coefficients (I_2 − I_3) M⁻¹_1 ... as expressions of p, the derived M⁻¹_i), else None."""

    parts: dict[str, StatePart] = field(default_factory=dict)
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


def _no_parameters(a: Assembly, name: str, rotor: Rotor, J: ca.SX) -> None:
    return None


@dataclass(frozen=True)
class RotorMode:
    """A rotor mode. rules: its scene-file rules; add_inputs(a, name, rotor): its inputs
    (value-reference order: in rotor order, after the other features'); add_parameters(a,
    name, rotor, J): its parameters after the rotor's J; torque_driven: Ω̇ follows from the
    motor torque (else add_inputs or add_parameters put Ω̇ into RotorSymbols.accel);
    fmu_inputs: its FMU inputs, "{}" standing for the rotor's name; motor_torque: the
    description of the output u_<name>, the torque that makes the known Ω̇, or None;
    works(name, scene): its motor does work in the scene (E_total is then not conserved)."""

    rules: ModeRules
    add_inputs: Callable[[Assembly, str, Rotor], None]
    fmu_inputs: tuple[str, ...]
    works: Callable[[str, SceneData], bool]
    add_parameters: Callable[[Assembly, str, Rotor, ca.SX], None] = _no_parameters
    torque_driven: bool = False
    motor_torque: Callable[[str], str] | None = None


def add_torque_input(a: Assembly, name: str, rotor: Rotor) -> None:
    """u_<name> (N·m): the motor torque on the rotor about its axis (positive spins it up;
    the body feels −u g). Start value: the scene's schedule at t = 0 (0 without one)."""
    sym = ca.SX.sym(f"u_{name}")
    a.input_blocks.append(sym)
    symbols(a).torques.append(sym)
    a.add(
        [f"u_{name}"],
        Kind.INPUT,
        [float(a.scene.input_start(f"u_{name}")[0])],
        "N.m",
        [f"motor torque on rotor {name} about its axis (the body feels -u_{name} along it)"],
    )


def add_inverse_inertia(a: Assembly, name: str, rotor: Rotor, J: ca.SX) -> None:
    """Ω̇ = u (1/J) − g·ω̇: 1/J once per parameter change, not a division per stage."""
    symbols(a).inv_J.append(a.derive(f"inv_J_{name}", 1 / J))


def add_speed_inputs(a: Assembly, name: str, rotor: Rotor) -> None:
    """Omega_<name> (rad/s, relative to the body) and its derivative Omega_dot_<name>
    (rad/s², the driver gives the schedule's; docs/theory.md §8.5)."""
    Om, Om_dot = ca.SX.sym(f"Omega_{name}"), ca.SX.sym(f"Omega_dot_{name}")
    a.input_blocks += [Om, Om_dot]
    rs = symbols(a)
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


TORQUE_MODE = RotorMode(
    TORQUE,
    add_inputs=add_torque_input,
    fmu_inputs=("u_{}",),
    # motor torques given as a schedule do work (§8.2)
    works=lambda name, scene: any(k.startswith("u_") for k in scene.inputs),
    add_parameters=add_inverse_inertia,
    torque_driven=True,
)
SPEED_MODE = RotorMode(
    SPEED,
    add_inputs=add_speed_inputs,
    fmu_inputs=("Omega_{}", "Omega_dot_{}"),
    works=lambda name, scene: True,  # its motor does work (§8.5)
    motor_torque=lambda name: f"motor torque that holds rotor {name} at Omega_{name} (speed mode)",
)
