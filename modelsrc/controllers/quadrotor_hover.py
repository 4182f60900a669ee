"""quadrotor_hover: position, altitude and attitude cascade with a mixer to four rotor commands (docs/theory.md §12.2).

For a plant with four command-mode propellers whose axes are all body +z (modelsrc.features.rotors,
mode_command; docs/theory.md §8.6, §8.8), m, I, the propellers' positions r_i, k_f, k_m and spin
directions s_i (the sign of each rotor's start rate) taken from the plant scene at build time.

Outer loop (the geometric controller of Lee, Leok and McClamroch, "Geometric tracking control of a
quadrotor UAV on SE(3)", CDC 2010, without feed-forward): with the target position x_d, yaw ψ_d and
the integral e of the height error (a discrete state, z_{k+1} = z_k + T_s (x_d,3 − x_3)),

    a = [k_pxy (x_d − x) − k_dxy v]_{1,2},  a_3 = k_pz (x_d,3 − x_3) − k_dz v_3 + k_iz e,
    F = m (a − g)  (world; g the plant's gravity),  b3_d = F/|F|,
    b2_d = b3_d × (cos ψ_d, sin ψ_d, 0) normalised,  b1_d = b2_d × b3_d,  R_d = [b1_d b2_d b3_d],
    T = F · R e_3  (the collective thrust along the body axis).

Inner loop: e_R = ½ vee(R_dᵀ R − Rᵀ R_d), τ = I (−K_R e_R − K_w ω) (body), K_R = diag(k_R, k_R,
k_Rz), K_w = diag(k_w, k_w, k_wz): yaw has its own, lower gains, as the drag torques that turn the
body are two decades weaker than the thrust moments; the gyroscopic term and the rotors' reactions
are left to the feedback.

Mixer: the rotors' thrusts f_i = k_f Ω_i² along e_3 give T = Σ f_i and τ = Σ (r_i × e_3 − s_i
(k_m/k_f) e_3) f_i (thrust moments and drag torques −k_m Ω|Ω| e_3, §8.6): a 4×4 matrix M, inverted
at build time; f = M⁻¹ (T, τ), each clipped to [0, k_f Ω_max²], and the command Ω_cmd,i = s_i √(f_i/k_f).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..quaternion import rotation_matrix
from ..scene import Scene
from ..scene_reader import SceneReader
from .controller import CKind, ControllerModel, CVar, ordered_variables

SECTION_KEYS = {
    "gains": frozenset({"k_pxy", "k_dxy", "k_pz", "k_dz", "k_iz", "k_R", "k_w", "k_Rz", "k_wz"}),
    "limits": frozenset({"rotor_speed"}),
    "target": frozenset({"position", "yaw"}),
}
DEFAULT_GAINS = {"k_pxy": 1.0, "k_dxy": 1.8, "k_pz": 4.0, "k_dz": 4.0, "k_iz": 0.0, "k_R": 100.0, "k_w": 20.0,
                 "k_Rz": 4.0, "k_wz": 4.0}  # fmt: skip
GAIN_UNITS = {"k_pxy": "1/s2", "k_dxy": "1/s", "k_pz": "1/s2", "k_dz": "1/s", "k_iz": "1/s3", "k_R": "1/s2",
              "k_w": "1/s", "k_Rz": "1/s2", "k_wz": "1/s"}  # fmt: skip
E3 = np.array([0.0, 0.0, 1.0])


def plant_propellers(rd: SceneReader, scene: Scene) -> tuple[list[str], np.ndarray, np.ndarray, float]:
    """(rotor names, spin signs s_i, the mixer M (4×4: T, τ from the thrusts), k_f) of a plant with
    four command-mode propellers along body +z, equal k_f, a start rate of either sign each."""
    rotors = {n: r for n, r in scene.rotors.items() if r.mode == "command" and r.propeller}
    if len(rotors) != 4 or len(scene.rotors) != 4:
        raise rd.fail("plant", f"scene {scene.name!r} has {len(rotors)} command-mode propellers "
                      f"(of {len(scene.rotors)} rotors); quadrotor_hover needs exactly 4")  # fmt: skip
    if scene.mass is None or scene.g is None or not (abs(scene.g[0]) == abs(scene.g[1]) == 0.0 and scene.g[2] < 0):
        raise rd.fail("plant", f"scene {scene.name!r}: quadrotor_hover needs translation and gravity along world -z")
    names = list(rotors)
    for n, r in rotors.items():
        if not np.array_equal(np.asarray(r.axis, dtype=float), E3):
            raise rd.fail("plant", f"scene {scene.name!r}: rotor {n} axis {list(r.axis)} is not body +z")
        if r.Omega0 == 0.0:
            raise rd.fail(
                "plant", f"scene {scene.name!r}: rotor {n} has start rate 0; its sign gives the spin direction"
            )
        if r.k_f != rotors[names[0]].k_f:
            raise rd.fail("plant", f"scene {scene.name!r}: the rotors' k_f differ ({r.k_f} and {rotors[names[0]].k_f})")
    k_f = float(rotors[names[0]].k_f)
    s = np.array([np.sign(rotors[n].Omega0) for n in names])
    arms = [np.asarray(rotors[n].position, dtype=float) for n in names]  # propellers: positions given
    M = np.vstack([np.ones(4), np.column_stack([np.cross(r, E3) - s[i] * rotors[n].k_m / k_f * E3
                                                for i, (n, r) in enumerate(zip(names, arms))])])  # fmt: skip
    if abs(np.linalg.det(M)) < 1e-12:
        raise rd.fail(
            "plant", f"scene {scene.name!r}: the rotors' thrusts and torques do not span (T, τ): singular mixer"
        )
    return names, s, M, k_f


def build(rd: SceneReader, name: str, description: str, scene: Scene, Ts: float) -> ControllerModel:
    """The quadrotor_hover controller of a file (module docstring) for the plant `scene`."""
    names, s, M, k_f = plant_propellers(rd, scene)
    gains, limits, target = rd.section("gains"), rd.section("limits"), rd.section("target")
    g_vals = {k: rd.parameter(f"gains.{k}", gains.get(k, v), nonneg=True) for k, v in DEFAULT_GAINS.items()}
    om_max = rd.parameter("limits.rotor_speed", limits.get("rotor_speed", 1000.0), positive=True)
    x_d = rd.vector("target.position", target.get("position", list(scene.x0)), 3)
    yaw = rd.number("target.yaw", target.get("yaw", 0.0))

    X, V = [f"x_cm[{i}]" for i in (1, 2, 3)], [f"v_cm[{i}]" for i in (1, 2, 3)]
    Q, W = [f"q[{i}]" for i in (1, 2, 3, 4)], [f"w_body[{i}]" for i in (1, 2, 3)]
    inputs = [
        CVar(n, CKind.INPUT, float(scene.x0[i]), "m", "position of the plant's centre of mass, world")
        for i, n in enumerate(X)
    ]
    inputs += [CVar(n, CKind.INPUT, 0.0, "m/s", "velocity of the plant's centre of mass, world") for n in V]
    inputs += [
        CVar(n, CKind.INPUT, 1.0 if n == "q[1]" else 0.0, None, "attitude of the plant (body -> world)") for n in Q
    ]
    inputs += [CVar(n, CKind.INPUT, 0.0, "rad/s", "angular velocity of the plant, body frame") for n in W]
    tunable = [CVar(k, CKind.PARAM_TUNABLE, v, GAIN_UNITS[k], f"gain {k}, >= 0") for k, v in g_vals.items()]
    tunable += [CVar("Omega_max", CKind.PARAM_TUNABLE, om_max, "rad/s", "largest rotor speed command, > 0")]
    tunable += [
        CVar(f"x_d[{i + 1}]", CKind.PARAM_TUNABLE, float(x_d[i]), "m", "target position, world") for i in range(3)
    ]
    tunable += [CVar("psi_d", CKind.PARAM_TUNABLE, yaw, "rad", "target yaw: heading of body x about world z")]
    fixed = [
        CVar("Ts", CKind.PARAM_FIXED, Ts, "s", "sample period: samples at t_start + k Ts, each a communication point")
    ]
    outputs = [
        CVar(f"Omega_cmd_{n}", CKind.OUTPUT, None, "rad/s", f"speed command of rotor {n} (held between samples)")
        for n in names
    ]
    states = [CVar("e_z_int", CKind.STATE, 0.0, "m.s", "integral of the height error x_d[3] - x_cm[3] (m s)")]
    variables = ordered_variables(inputs, tunable, fixed, outputs, states)

    u = ca.SX.sym("u", len(inputs))
    p = ca.SX.sym("p", len(tunable) + len(fixed))
    z = ca.SX.sym("z", 1)
    pn = [v.name for v in tunable + fixed]

    def P(n: str) -> ca.SX:
        return p[pn.index(n)]

    x, v, q, w = u[0:3], u[3:6], u[6:10], u[10:13]
    xd = ca.vertcat(P("x_d[1]"), P("x_d[2]"), P("x_d[3]"))
    a = ca.vertcat(P("k_pxy") * (xd[0] - x[0]) - P("k_dxy") * v[0], P("k_pxy") * (xd[1] - x[1]) - P("k_dxy") * v[1],
                   P("k_pz") * (xd[2] - x[2]) - P("k_dz") * v[2] + P("k_iz") * z[0])  # fmt: skip
    F = scene.mass * (a - ca.DM(np.asarray(scene.g, dtype=float)))
    b3 = F / ca.norm_2(F)
    c = ca.vertcat(ca.cos(P("psi_d")), ca.sin(P("psi_d")), 0)
    b2 = ca.cross(b3, c)
    b2 = b2 / ca.norm_2(b2)
    b1 = ca.cross(b2, b3)
    Rd = ca.horzcat(b1, b2, b3)
    R = rotation_matrix(q)
    E = 0.5 * (Rd.T @ R - R.T @ Rd)
    e_R = ca.vertcat(E[2, 1], E[0, 2], E[1, 0])
    K_R = ca.vertcat(P("k_R"), P("k_R"), P("k_Rz"))
    K_w = ca.vertcat(P("k_w"), P("k_w"), P("k_wz"))
    tau = ca.DM(np.asarray(scene.inertia, dtype=float)) @ (-K_R * e_R - K_w * w)
    T = ca.dot(F, R[:, 2])
    f = ca.DM(np.linalg.inv(M)) @ ca.vertcat(T, tau)
    f = ca.fmin(ca.fmax(f, 0), k_f * P("Omega_max") ** 2)
    y = ca.vertcat(*[float(s[i]) * ca.sqrt(f[i] / k_f) for i in range(4)])
    checks = [(P(k) >= 0, f"{k} >= 0") for k in DEFAULT_GAINS]
    checks += [(P("Omega_max") > 0, "Omega_max > 0"), (P("Ts") > 0, "Ts > 0")]
    functions = {
        "ctrl_output": ca.Function("ctrl_output", [u, p, z], [y], ["u", "p", "z"], ["y"]),
        "ctrl_update": ca.Function(
            "ctrl_update", [u, p, z], [z + P("Ts") * (xd[2] - x[2])], ["u", "p", "z"], ["z_next"]
        ),
        "ctrl_checks": ca.Function("ctrl_checks", [p], [ca.vertcat(*[cc for cc, _ in checks])], ["p"], ["ok"]),
    }
    feed = {o.name: X + V + Q + W for o in outputs}
    if not description:
        description = f"Position, altitude and attitude cascade with mixer for {scene.name}'s four propellers"
    return ControllerModel(name, description, scene.name, Ts, variables, functions, [t for _, t in checks], feed)
