"""attitude_torque_pd: quaternion-feedback PD attitude law commanding a body torque directly (docs/theory.md §12.3).

Wie, "Space Vehicle Dynamics and Control", §7.3 (Wie, Weiss & Arapostathis, J. Guid. Control
Dyn. 12 (1989)): with the error quaternion q_e = q_d* ⊗ q (body frame; q and q_d body -> world,
scalar first) the body torque is

    τ_body = −k_p sgn(q_e0) q_e,vec − k_d ω,

k_p in N·m (per unit of the error quaternion's vector part), k_d in N·m·s/rad: the gains act on
the torque itself, not through an inertia, so the law is the same for any plant with a body
torque input (`features.torque_body`). Each component is then clipped to [−tau_max, tau_max]
(N·m). No discrete state: the law is memoryless, sampled and held (zero-order hold) by the
generic sampled-data layer (docs/theory.md §12). A disturbance torque is not the controller's:
it stays on the plant's own input (e.g. torque_driven's tau_world, set by the system file).
Without the limit the law is rbcheck.baselines.rigid_body.AttitudePD's body torque.
"""

from __future__ import annotations

import casadi as ca

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
    "gains": frozenset({"k_p", "k_d"}),
    "limits": frozenset({"torque"}),
    "target": frozenset({"q"}),
}
TAU_NAMES = [f"tau_body[{i}]" for i in range(1, 4)]


def build(rd: SceneReader, name: str, description: str, scene: Scene, Ts: float) -> ControllerModel:
    """The attitude_torque_pd controller of a file (module docstring) for the plant `scene`,
    which must take a body torque (features.torque_body)."""
    if not scene.has("torque_body"):
        raise rd.fail("plant", f"scene {scene.name!r} has no body torque input (features.torque_body = true)")
    gains, limits, target = rd.section("gains"), rd.section("limits"), rd.section("target")
    k_p = rd.parameter("gains.k_p", gains.get("k_p", 1.0), nonneg=True)
    k_d = rd.parameter("gains.k_d", gains.get("k_d", 2.0), nonneg=True)
    tau_max = rd.parameter("limits.torque", limits.get("torque", 1e3), positive=True)
    qd = target_quaternion(rd, target)
    inputs = attitude_inputs()
    tunable = [
        CVar("k_p", CKind.PARAM_TUNABLE, k_p, "N.m", "proportional gain on the error quaternion's vector part, >= 0"),
        CVar("k_d", CKind.PARAM_TUNABLE, k_d, "N.m.s", "rate gain (N m s/rad), >= 0"),
        CVar("tau_max", CKind.PARAM_TUNABLE, tau_max, "N.m", "limit of each body-torque component (saturation), > 0"),
    ]
    tunable += target_parameters(qd)
    fixed = [
        CVar("Ts", CKind.PARAM_FIXED, Ts, "s", "sample period: samples at t_start + k Ts, each a communication point")
    ]
    outputs = [
        CVar(n, CKind.OUTPUT, None, "N.m", f"body torque on the plant, body axis {n[9]} (held between samples)")
        for n in TAU_NAMES
    ]
    variables = ordered_variables(inputs, tunable, fixed, outputs, [])

    u = ca.SX.sym("u", len(inputs))
    p = ca.SX.sym("p", len(tunable) + len(fixed))
    z = ca.SX.sym("z", 0)
    pn = [v.name for v in tunable + fixed]
    P = lambda n: p[pn.index(n)]
    q, w = u[0:4], u[4:7]
    qe, sgn = error_quaternion(P, q)
    tau = -P("k_p") * sgn * qe[1:4] - P("k_d") * w
    y = ca.fmin(ca.fmax(tau, -P("tau_max")), P("tau_max"))
    checks = [(P("k_p") >= 0, "k_p >= 0"), (P("k_d") >= 0, "k_d >= 0"), (P("tau_max") > 0, "tau_max > 0"),
              (P("Ts") > 0, "Ts > 0")]  # fmt: skip
    checks.append(target_check(P))
    functions = {
        "ctrl_output": ca.Function("ctrl_output", [u, p, z], [y], ["u", "p", "z"], ["y"]),
        "ctrl_update": ca.Function("ctrl_update", [u, p, z], [z], ["u", "p", "z"], ["z_next"]),
        "ctrl_checks": ca.Function("ctrl_checks", [p], [ca.vertcat(*[c for c, _ in checks])], ["p"], ["ok"]),
    }
    feed = {o.name: Q_NAMES + W_NAMES for o in outputs}
    if not description:
        description = f"Quaternion-feedback PD attitude law (Wie §7.3) commanding {scene.name}'s body torque"
    if Ts <= 0:
        raise ModelInputError(f"controller {name}: sample_period = {Ts} must be > 0")
    return ControllerModel(name, description, scene.name, Ts, variables, functions, [t for _, t in checks], feed)
