"""The speed-command rotor mode ("command"): a motor that follows a speed command Ω_cmd with a first-order lag.

The motor model of multirotor simulators (RotorS, Furrer et al. 2016; Flightmare, Song et
al. 2020; docs/theory.md §8.8): the rotor's rate relative to the body Ω is a state that
follows the input Omega_cmd_<name> (rad/s) with the time constant tau_m (s, [rotors.<name>]
tau_m, at least TAU_M_MIN):

    Ω̇ = (Ω_cmd − Ω) / τ_m

so a held (zero-order hold) command changes Ω continuously and the reaction torque J Ω̇ on
the body stays bounded (a speed-mode rotor's Ω would jump, §8.5). The body feels −J Ω̇ g as
with a speed-mode rotor (its axial inertia stays in I − Σ J g gᵀ), the output u_<name> is
the motor torque J (Ω̇ + g·ω̇) + k_m Ω|Ω|, and a propeller's thrust and drag (§8.6) take Ω.
This module is the whole mode: the rotors find it (feature.py).
"""

from __future__ import annotations

import casadi as ca

from ...assembly import Assembly
from ...errors import ModelInputError
from ...variables import Kind
from .modes import RotorMode, symbols
from .scene_file import ModeRules, Rotor

# The shortest motor time constant (s). The lag adds -1/τ_m to the Jacobian of the rotation
# block, so the automatic sub-steps of the explicit methods keep h <= ~τ_m (their rate limit,
# docs/theory.md §5.4): below 1 µs a second of simulated time costs over 1e6 steps, while real
# motors (RotorS, Flightmare: 1e-2 .. 5e-2 s) are four decades slower. A shorter lag is a
# speed-mode rotor (§8.5).
TAU_M_MIN = 1e-6

RULES = ModeRules(
    "command",
    state=True,
    propeller=True,
    keys=frozenset({"tau_m"}),
    inputs=("Omega_cmd_{}",),
    reserved=("cmd_",),  # a rotor cmd_<x> would have the input Omega_cmd_<x> of a command rotor <x>
)


def commands(a: Assembly) -> dict[str, ca.SX]:
    """This mode's record: rotor name -> its command symbol Omega_cmd_<name>."""
    return a.feature_state("rotors.command", dict)


def add_command_input(a: Assembly, name: str, rotor: Rotor) -> None:
    """Omega_cmd_<name> (rad/s): the commanded rate relative to the body; start value the
    schedule's at t = 0 (0 without one)."""
    sym = ca.SX.sym(f"Omega_cmd_{name}")
    a.input_blocks.append(sym)
    commands(a)[name] = sym
    a.add(
        [f"Omega_cmd_{name}"],
        Kind.INPUT,
        [float(a.scene.input_start(f"Omega_cmd_{name}")[0])],
        "rad/s",
        [f"speed command of rotor {name}: its rate relative to the body follows it with the lag tau_m_{name}"],
    )


def add_lag(a: Assembly, name: str, rotor: Rotor, J: ca.SX) -> None:
    """tau_m_<name> (s, >= TAU_M_MIN; the scene's value checked here, a value set through the
    FMU by the FMU's checks), 1/τ_m derived once, and Ω̇ = (Ω_cmd − Ω)/τ_m (rad/s²), the rate
    the body's equations and the rotor's state take (§8.8)."""
    tau_m = rotor.settings["tau_m"]
    if not tau_m >= TAU_M_MIN:
        raise ModelInputError(
            f"scene file {a.scene.path}: field 'rotors.{name}.tau_m': must be >= {TAU_M_MIN:g} s (a shorter lag "
            f'needs steps below it; use mode = "speed" for a rate that follows at once), got {tau_m:g}'
        )
    tau = ca.SX.sym(f"tau_m_{name}")
    a.parameter(tau, [f"tau_m_{name}"], [tau_m], "s", [f"motor time constant of rotor {name} (command mode)"])
    a.checks.append((f"tau_m_{name} must be >= {TAU_M_MIN:g} s (the motor time constant)", tau - TAU_M_MIN, False))
    inv_tau = a.derive(f"inv_tau_m_{name}", 1 / tau)
    rs = symbols(a)
    rs.accel[name] = (commands(a)[name] - rs.speed[name]) * inv_tau


MODE = RotorMode(
    RULES,
    add_inputs=add_command_input,
    fmu_inputs=("Omega_cmd_{}",),
    works=lambda name, scene: True,  # the motor does work
    add_parameters=add_lag,
    motor_torque=lambda name: f"motor torque that makes rotor {name} follow Omega_cmd_{name} (command mode)",
)
