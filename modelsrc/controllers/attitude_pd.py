"""attitude_pd: quaternion-feedback PD(+I) attitude law for a body with three reaction wheels (docs/theory.md §12.1).

Wie, "Space Vehicle Dynamics and Control", §7.3: with the error quaternion q_e = q_d* ⊗ q
(body frame; q and q_d body -> world, scalar first) the body torque is

    τ_c = −I_r (k_p sgn(q_e0) q_e,vec + k_d ω + k_i z),   z_{k+1} = z_k + T_s sgn(q_e0) q_e,vec,

I_r = I − Σ J g gᵀ the inertia the wheels push against (docs/theory.md §8.1), and the wheels
apply it with the motor torques u = −G⁻¹ τ_c (the body feels −Σ g_i u_i; G the wheel axes as
columns). I_r and G are the plant scene's, fixed at build time. Each u_i is then limited:

1. saturation: u_i is clipped to [−u_max_<i>, u_max_<i>] (N·m);
2. wheel-speed limit: a wheel at or beyond its limit, |Ω_i| ≥ Omega_max_<i>, gets no torque
   that would speed it up further: u_i = 0 when Ω_i ≥ Omega_max_<i> and u_i > 0, or
   Ω_i ≤ −Omega_max_<i> and u_i < 0 (u_i > 0 accelerates Ω_i: J (Ω̇_i + g_i·ω̇) = u_i, §8.2).
   Torque that slows the wheel passes.

Anti-windup by conditional integration (Åström & Hägglund, "Advanced PID Control", ISA 2006,
ch. 3, integrator windup; docs/theory.md §12.1): with anti_windup = 1 (the default) a sample's
increment T_s sgn(q_e0) q_e,vec is not added when it would move the unlimited command u further
from what a limited wheel applies, i.e. when Δu_i (u_i − y_i) > 0 for some wheel i, where
Δu = k_i G⁻¹ I_r T_s sgn(q_e0) q_e,vec is the increment's effect on u and y_i the limited output;
anti_windup = 0 integrates always. With k_i = 0 (the default) Δu = 0: z integrates always and is
unused.
Without saturation and speed cut and with k_i = 0 the law is rbcheck.closed_forms.slew.PDSlew.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import ModelInputError
from ..scene import Scene
from ..scene_reader import SceneReader
from .attitude_error import (
    Q_NAMES,
    W_NAMES,
    attitude_inputs,
    error_quaternion,
    target_check,
    target_parameters,
    target_quaternion,
)
from .controller import CKind, ControllerModel, CVar, ordered_variables

SECTION_KEYS = {
    "gains": frozenset({"k_p", "k_d", "k_i"}),
    "limits": frozenset({"torque", "wheel_speed", "anti_windup"}),
    "target": frozenset({"q"}),
}
Z_NAMES = [f"e_int[{i}]" for i in range(1, 4)]


def plant_wheels(rd: SceneReader, scene: Scene) -> tuple[list[str], np.ndarray, np.ndarray]:
    """(wheel names, G with the wheel axes as columns, I_r) of a plant with three torque-mode
    wheels with independent axes; ModelInputError naming the plant otherwise."""
    wheels = [n for n, r in scene.rotors.items() if r.mode == "torque"]
    if len(wheels) != 3:
        raise rd.fail(
            "plant", f"scene {scene.name!r} has {len(wheels)} torque-mode wheels; attitude_pd needs exactly 3"
        )
    G = np.column_stack([scene.rotors[n].axis for n in wheels])
    if abs(np.linalg.det(G)) < 1e-6:
        raise rd.fail(
            "plant",
            f"scene {scene.name!r}: the wheel axes {wheels} are not independent (det G = {np.linalg.det(G):.3g})",
        )
    I_r = np.asarray(scene.inertia, dtype=float) - sum(
        scene.rotors[n].J * np.outer(scene.rotors[n].axis, scene.rotors[n].axis) for n in wheels
    )
    return wheels, G, I_r


def build(rd: SceneReader, name: str, description: str, scene: Scene, Ts: float) -> ControllerModel:
    """The attitude_pd controller of a file (module docstring) for the plant `scene`."""
    wheels, G, I_r = plant_wheels(rd, scene)
    gains, limits, target = rd.section("gains"), rd.section("limits"), rd.section("target")
    k_p = rd.parameter("gains.k_p", gains.get("k_p", 0.5), nonneg=True)
    k_d = rd.parameter("gains.k_d", gains.get("k_d", 1.0), nonneg=True)
    k_i = rd.parameter("gains.k_i", gains.get("k_i", 0.0), nonneg=True)
    u_max = rd.parameter("limits.torque", limits.get("torque", 1.0), positive=True)
    w_max = rd.parameter("limits.wheel_speed", limits.get("wheel_speed", 1000.0), positive=True)
    anti_windup = rd.number("limits.anti_windup", limits.get("anti_windup", 1))
    if anti_windup not in (0.0, 1.0):
        raise rd.fail("limits.anti_windup", f"must be 1 (conditional integration) or 0 (none), got {anti_windup!r}")
    qd = target_quaternion(rd, target)

    omega_names = [f"Omega_{w}" for w in wheels]
    inputs = attitude_inputs()
    inputs += [
        CVar(n, CKind.INPUT, 0.0, "rad/s", f"rate of wheel {w} relative to the body (for the speed limit)")
        for n, w in zip(omega_names, wheels)
    ]
    tunable = [
        CVar("k_p", CKind.PARAM_TUNABLE, k_p, "1/s2", "proportional gain on the error quaternion's vector part, >= 0"),
        CVar("k_d", CKind.PARAM_TUNABLE, k_d, "1/s", "rate gain, >= 0"),
        CVar("k_i", CKind.PARAM_TUNABLE, k_i, None, "integral gain (1/s^3), >= 0; 0: no integral term"),
    ]
    tunable += [
        CVar(f"u_max_{w}", CKind.PARAM_TUNABLE, u_max, "N.m", f"torque limit of wheel {w} (saturation), > 0")
        for w in wheels
    ]
    tunable += [
        CVar(f"Omega_max_{w}", CKind.PARAM_TUNABLE, w_max, "rad/s", f"speed limit of wheel {w}, > 0") for w in wheels
    ]
    tunable.append(
        CVar("anti_windup", CKind.PARAM_TUNABLE, anti_windup, None,
             "1: the integral holds while a limited wheel's torque would be pushed further (conditional "
             "integration); 0: it always integrates")
    )  # fmt: skip
    tunable += target_parameters(qd)
    fixed = [
        CVar("Ts", CKind.PARAM_FIXED, Ts, "s", "sample period: samples at t_start + k Ts, each a communication point")
    ]
    outputs = [
        CVar(f"u_{w}", CKind.OUTPUT, None, "N.m", f"motor torque of wheel {w} (held between samples)") for w in wheels
    ]
    states = [
        CVar(n, CKind.STATE, 0.0, None, "integral of sgn(q_e0) q_e,vec (rad s), the discrete state") for n in Z_NAMES
    ]
    variables = ordered_variables(inputs, tunable, fixed, outputs, states)

    u = ca.SX.sym("u", len(inputs))
    p = ca.SX.sym("p", len(tunable) + len(fixed))
    z = ca.SX.sym("z", 3)
    pn = [v.name for v in tunable + fixed]
    P = lambda n: p[pn.index(n)]
    q, w, Om = u[0:4], u[4:7], u[7:10]
    qe, sgn = error_quaternion(P, q)
    tau_c = -ca.DM(I_r) @ (P("k_p") * sgn * qe[1:4] + P("k_d") * w + P("k_i") * z)
    u_raw = -ca.DM(np.linalg.inv(G)) @ tau_c
    dz = P("Ts") * sgn * qe[1:4]  # this sample's increment of the integral
    du = ca.DM(np.linalg.inv(G) @ I_r) @ (P("k_i") * dz)  # its effect on u_raw
    y = []
    for i, wname in enumerate(wheels):
        lim, om_max = P(f"u_max_{wname}"), P(f"Omega_max_{wname}")
        ui = ca.fmin(ca.fmax(u_raw[i], -lim), lim)
        cut = ca.logic_or(ca.logic_and(Om[i] >= om_max, ui > 0), ca.logic_and(Om[i] <= -om_max, ui < 0))
        y.append(ca.if_else(cut, 0.0, ui))
    # conditional integration: hold z when the increment pushes some wheel's command further past its limit
    pushes = [du[i] * (u_raw[i] - y[i]) > 0 for i in range(len(wheels))]
    hold = ca.logic_and(P("anti_windup") == 1, ca.logic_or(ca.logic_or(pushes[0], pushes[1]), pushes[2]))
    checks = [(P("k_p") >= 0, "k_p >= 0"), (P("k_d") >= 0, "k_d >= 0"), (P("k_i") >= 0, "k_i >= 0"),
              (P("Ts") > 0, "Ts > 0"),
              (ca.logic_or(P("anti_windup") == 0, P("anti_windup") == 1), "anti_windup = 0 or 1")]  # fmt: skip
    checks += [(P(f"u_max_{wn}") > 0, f"u_max_{wn} > 0") for wn in wheels]
    checks += [(P(f"Omega_max_{wn}") > 0, f"Omega_max_{wn} > 0") for wn in wheels]
    checks.append(target_check(P))
    functions = {
        "ctrl_output": ca.Function("ctrl_output", [u, p, z], [ca.vertcat(*y)], ["u", "p", "z"], ["y"]),
        "ctrl_update": ca.Function(
            "ctrl_update", [u, p, z], [ca.if_else(hold, z, z + dz)], ["u", "p", "z"], ["z_next"]
        ),
        "ctrl_checks": ca.Function("ctrl_checks", [p], [ca.vertcat(*[c for c, _ in checks])], ["p"], ["ok"]),
    }
    ins = Q_NAMES + W_NAMES
    feed = {o.name: ins + [f"Omega_{o.name[2:]}"] for o in outputs}
    if not description:
        description = f"Quaternion-feedback PD attitude law (Wie §7.3) for {scene.name}'s three wheels"
    if Ts <= 0:
        raise ModelInputError(f"controller {name}: sample_period = {Ts} must be > 0")
    return ControllerModel(name, description, scene.name, Ts, variables, functions, [t for _, t in checks], feed)
