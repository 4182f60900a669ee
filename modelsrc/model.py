"""Assembles a scene's CasADi model: the equations of rigid_body.py, the FMI variables and the generated functions.

Only what the scene uses is built: a torque-free scene has no torque inputs and no
gravity parameters, and derived outputs not requested are not computed. Each feature
has its builder (a screenful each) that adds its symbols, variables, torques and checks
to an `Assembly`; `build_model` runs them in value-reference order. The builders of
the moving reference point (free flight, forces at points, the moving pivot) are in
`free_motion.py`.

State x = (q[1..4], w_body[1..3]): unit quaternion body -> world (scalar first) and
angular velocity (rad/s, body frame); a free body adds (x_cm, v_cm), a moving pivot
(x_pivot, v_pivot) (m, m/s, world). See docs/theory.md §6 for the assembly.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from . import free_motion as fm
from . import rigid_body as rb
from .inertia import inertia_conditions, parallel_axis_shift
from .methods import METHODS, WORK_LIMIT
from .model_functions import derived_outputs, model_functions
from .quaternion import quat_derivative, rotation_matrix
from .scene import QUAT_NORM_TOL, Scene
from .variables import Kind, Variable, vector_names


@dataclass
class RigidBodyModel:
    """The model of one scene.

    variables: all FMI variables in value-reference order (vr = index), laid out as
    [time | states x | inputs u | parameters p | derived outputs y | derivatives dx],
    the same layout as the C layer's value buffer. functions: the CasADi functions whose C is
    generated (model_step_<method>, model_outputs, model_checks, model_project, model_rhs,
    model_rate, model_jac). checks: (text, strict) of each entry of model_checks' output
    (holds if > 0 / >= 0). methods: integrator names compiled in, in METHODS order.
    """

    scene: Scene
    variables: list[Variable]
    nx: int
    nu: int
    np_: int
    ny: int
    functions: dict[str, ca.Function]
    checks: list[tuple[str, bool]]
    h_max_index: int
    methods: tuple[str, ...]
    default_method: str

    @property
    def offsets(self) -> dict[str, int]:
        """Buffer offsets of the five blocks (x, u, p, y, dx)."""
        y = 1 + self.nx + self.nu + self.np_
        return {"x": 1, "u": 1 + self.nx, "p": 1 + self.nx + self.nu, "y": y, "dx": y + self.ny}

    def vr(self, name: str) -> int:
        """Value reference of a variable by name."""
        for i, v in enumerate(self.variables):
            if v.name == name:
                return i
        raise KeyError(name)


@dataclass
class Assembly:
    """The model under construction, filled feature by feature.

    q, w: state symbols; R: rotation body -> world of q (any |q|); I: inertia about the
    point the body turns about (kg·m², body); I_cm: about the centre of mass;
    tau: total torque (N·m, body); tau_conservative: all but friction (the splittings'
    kick); V: potential energy (J) or None; c: friction coefficient symbol or None,
    c_index its position in p; checks: (text, expression, strict) evaluated at
    initialisation. The moving reference point (free_motion.py): pos, vel (m, m/s,
    world) its states or None; accel (m/s², world) its acceleration; force: the sum of
    the external forces but the pivot's (N, world); mass, g, r_cm, a_pivot: symbols or
    None; force_inputs: force point name -> its input symbol (N, in its frame)."""

    scene: Scene
    q: ca.SX = field(default_factory=lambda: ca.SX.sym("q", 4))
    w: ca.SX = field(default_factory=lambda: ca.SX.sym("w", 3))
    variables: list[Variable] = field(default_factory=list)
    u_parts: list[ca.SX] = field(default_factory=list)
    p_parts: list[ca.SX] = field(default_factory=list)
    checks: list[tuple[str, ca.SX, bool]] = field(default_factory=list)
    tau: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    I: ca.SX = field(default_factory=lambda: ca.SX.zeros(3, 3))  # set by add_inertia
    V: ca.SX | None = None
    c: ca.SX | None = None
    c_index: int | None = None
    r_sensor: ca.SX | None = None
    pos: ca.SX | None = None
    vel: ca.SX | None = None
    accel: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    force: ca.SX = field(default_factory=lambda: ca.SX.zeros(3))
    mass: ca.SX | None = None
    g: ca.SX | None = None
    r_cm: ca.SX | None = None
    a_pivot: ca.SX | None = None
    force_inputs: dict[str, ca.SX] = field(default_factory=dict)
    h_max_index: int = -1
    method: ca.SX = field(default_factory=lambda: ca.SX.sym("method"))  # the selected method's value

    def __post_init__(self) -> None:
        self.R = rotation_matrix(self.q)  # a rotation for any |q| (Model Exchange lets |q| drift)
        self.tau_conservative = self.tau
        self.I_cm = self.I

    @property
    def x(self) -> ca.SX:
        if self.pos is None or self.vel is None:
            return ca.vertcat(self.q, self.w)
        return ca.vertcat(self.q, self.w, self.pos, self.vel)

    @property
    def u(self) -> ca.SX:
        return ca.vertcat(*self.u_parts) if self.u_parts else ca.SX.zeros(0, 1)

    @property
    def p(self) -> ca.SX:
        return ca.vertcat(*self.p_parts)

    def add(self, names: list[str], kind: Kind, starts: list[float | None], unit: str | None, descs: list[str]) -> None:
        """Append one variable per name (value references follow in order)."""
        for n, s, d in zip(names, starts, descs):
            self.variables.append(Variable(n, kind, None if s is None else float(s), unit, d))

    def parameter(
        self, sym: ca.SX, names: list[str], starts, unit: str | None, descs: list[str], kind: Kind = Kind.PARAM_FIXED
    ) -> int:
        """A parameter block: its symbol joins p, its variables the table; returns its offset in p."""
        offset = sum(part.shape[0] for part in self.p_parts)
        self.p_parts.append(sym)
        self.add(names, kind, list(starts), unit, descs)
        return offset


# --- builders, in value-reference order: states, inputs, parameters (docs/theory.md §6) ---


def add_states(a: Assembly) -> None:
    """q[1..4] and w_body[1..3]: their start values are the scene's initial state."""
    sc = a.scene
    a.variables.append(Variable("time", Kind.INDEPENDENT, None, "s", "simulation time"))
    a.add(
        vector_names("q", 4),
        Kind.STATE,
        list(sc.q0),
        None,
        [f"orientation quaternion body->world, component {c} (scalar first)" for c in "wxyz"],
    )
    a.add(
        vector_names("w_body", 3),
        Kind.STATE,
        list(sc.w0),
        "rad/s",
        [f"angular velocity, body axis {i}" for i in (1, 2, 3)],
    )


def add_torque_inputs(a: Assembly) -> None:
    """Inputs tau_body (N·m, body) and tau_world (N·m, world, turned into the body by Rᵀ)."""
    for feature, name, frame, to_body in (
        ("torque_body", "tau_body", "body", lambda t: t),
        ("torque_world", "tau_world", "world", lambda t: rb.world_to_body_torque(a.R, t)),
    ):
        if not a.scene.has(feature):
            continue
        sym = ca.SX.sym(name, 3)
        a.u_parts.append(sym)
        a.tau = a.tau + to_body(sym)
        a.add(
            vector_names(name, 3),
            Kind.INPUT,
            list(a.scene.input_start(name)),
            "N.m",
            [f"applied torque, {frame} axis {i}" for i in (1, 2, 3)],
        )


def add_inertia(a: Assembly) -> None:
    """Principal moments (3 parameters) or the full tensor (9), about the centre of mass,
    with the validity conditions of docs/theory.md §3.4 as checks."""
    sc = a.scene
    if sc.principal:
        Ip = ca.SX.sym("I_principal", 3)
        a.parameter(
            Ip,
            vector_names("I_principal", 3),
            np.diag(sc.inertia),
            "kg.m2",
            [f"principal moment of inertia about body axis {i}, centre of mass" for i in (1, 2, 3)],
        )
        a.I = a.I_cm = ca.diag(Ip)
        names = ["I_principal[1]", "0", "0", "0", "I_principal[2]", "0", "0", "0", "I_principal[3]"]
        a.checks += [c for c in inertia_conditions(a.I, names) if "symmetric" not in c[0]]
    else:
        Iv = ca.SX.sym("I", 9)  # row major I[1,1], I[1,2], ..., I[3,3]
        names = [f"I[{i},{j}]" for i in range(1, 4) for j in range(1, 4)]
        a.parameter(
            Iv,
            names,
            sc.inertia.ravel(),
            "kg.m2",
            [f"inertia tensor entry {n[1:]} about the centre of mass, body frame" for n in names],
        )
        a.I = a.I_cm = ca.reshape(Iv, 3, 3).T
        a.checks += inertia_conditions(a.I, names)


def add_gravity(a: Assembly) -> None:
    """Heavy top: rotation about the pivot, inertia shifted there (parallel axes), the
    torque and potential of gravity (docs/theory.md §4.1); about a moving pivot, gravity
    g − a_pivot (§7.3). (Gravity on a free body: free_motion.add_translation.)"""
    sc = a.scene
    if not sc.has("gravity") or sc.has("translation"):
        return
    m, r_cm, g = ca.SX.sym("mass"), ca.SX.sym("r_cm", 3), ca.SX.sym("g", 3)
    a.parameter(m, ["mass"], [sc.mass], "kg", ["mass of the body"])
    a.parameter(
        r_cm, vector_names("r_cm", 3), sc.r_cm, "m", [f"pivot -> centre of mass, body axis {i}" for i in (1, 2, 3)]
    )
    a.parameter(
        g, vector_names("g", 3), sc.g, "m/s2", [f"gravitational acceleration, world axis {i}" for i in (1, 2, 3)]
    )
    a.checks.append(("mass must be > 0", m, True))
    a.mass, a.r_cm, a.g = m, r_cm, g
    a.I = parallel_axis_shift(a.I, m, r_cm)
    if a.a_pivot is None:
        a.tau = a.tau + rb.gravity_torque(a.R, r_cm, m, g)
        a.V = rb.potential_energy(a.R, r_cm, m, g)
    else:
        fm.add_moving_pivot_dynamics(a)


def add_friction(a: Assembly) -> None:
    """Viscous friction −c ω (docs/theory.md §4.3); not part of the splittings' kick,
    which damp it exactly."""
    a.tau_conservative = a.tau
    if not a.scene.has("friction"):
        return
    a.c = ca.SX.sym("c_friction")
    a.c_index = a.parameter(
        a.c, ["c_friction"], [a.scene.c_friction], "N.m.s/rad", ["viscous friction coefficient: torque -c*w_body"]
    )
    a.checks.append(("c_friction must be >= 0", a.c, False))
    a.tau = a.tau + rb.friction_torque(a.w, a.c)


def add_sensor(a: Assembly) -> None:
    """The body-fixed sensor point r_sensor (m, body frame, from the rotation point)."""
    if "sensor" not in a.scene.outputs:
        return
    a.r_sensor = ca.SX.sym("r_sensor", 3)
    a.parameter(
        a.r_sensor,
        vector_names("r_sensor", 3),
        a.scene.sensor_point,
        "m",
        [f"sensor point from the rotation point, body axis {i}" for i in (1, 2, 3)],
    )


def add_step_controls(a: Assembly) -> None:
    """h_max and work_limit (tunable) and the checks that depend on the method and the state."""
    h_max = ca.SX.sym("h_max")
    a.h_max_index = len(a.variables)
    a.parameter(
        h_max,
        ["h_max"],
        [a.scene.h_max],
        "s",
        ["maximum internal integrator step; each doStep takes ceil(H/h_max) equal substeps"],
        Kind.PARAM_TUNABLE,
    )
    a.checks.append(("h_max must be > 0", h_max, True))
    work_limit = ca.SX.sym("work_limit")
    a.parameter(
        work_limit,
        ["work_limit"],
        [WORK_LIMIT],
        None,
        [
            "most work one doStep may do, in right-hand-side evaluations (one internal step costs "
            + ", ".join(f"{m} {METHODS[m].cost:g}" for m in a.scene.methods)
            + "; retries count); a doStep that would need more is refused before it starts"
        ],
        Kind.PARAM_TUNABLE,
    )
    a.checks.append(("work_limit must be > 0", work_limit, True))
    off = ca.fmax(ca.fmax(ca.fabs(a.I[0, 1]), ca.fabs(a.I[0, 2])), ca.fabs(a.I[1, 2]))
    for name in a.scene.methods:
        if METHODS[name].needs_principal:
            a.checks.append(
                (
                    f"method {name} needs principal axes about the rotation point: r_cm along one body axis",
                    ca.if_else(a.method == METHODS[name].value, 1e-12 * ca.trace(a.I) - off, 1),
                    False,
                )
            )
    qn = ca.norm_2(a.q)
    a.checks.append(
        (f"quaternion q must have unit norm (| |q| - 1 | <= {QUAT_NORM_TOL:g})", QUAT_NORM_TOL - ca.fabs(qn - 1), False)
    )


BUILDERS: tuple[Callable[[Assembly], None], ...] = (
    add_states,
    fm.add_motion_states,
    add_torque_inputs,
    fm.add_force_inputs,
    fm.add_pivot_input,
    add_inertia,
    add_gravity,
    fm.add_translation,
    fm.add_force_points,
    add_friction,
    add_sensor,
    add_step_controls,
)


# unit of a state -> unit of its time derivative (q is dimensionless)
DERIVATIVE_UNIT = {None: "1/s", "rad/s": "rad/s2", "m": "m/s", "m/s": "m/s2"}


def angular_acceleration(a: Assembly) -> ca.SX:
    """ω̇ (rad/s², body): Euler's equations, or zero when the rate is prescribed (held at
    a constant rate about a fixed axis: d/dt Rᵀ Ω = −ω × ω = 0; docs/theory.md §4.4)."""
    if a.scene.has("prescribed_rate"):
        return ca.SX.zeros(3)
    return rb.euler_rhs(a.I, a.w, a.tau)


def build_model(scene: Scene) -> RigidBodyModel:
    """Assemble the equations of rigid_body.py for a scene (docs/theory.md §6)."""
    a = Assembly(scene)
    for builder in BUILDERS:
        builder(a)
    a.accel = fm.reference_acceleration(a)
    w_dot = angular_acceleration(a)
    xdot = ca.vertcat(quat_derivative(a.q, a.w), w_dot)
    if a.pos is not None and a.vel is not None:
        xdot = ca.vertcat(xdot, a.vel, a.accel)  # ẋ = v, v̇ = a (docs/theory.md §7.1, §7.3)
    y = derived_outputs(a, w_dot)
    functions = model_functions(a, xdot, y)
    nx = a.x.shape[0]
    for i in range(nx):  # state derivatives (Model Exchange), their variables after the outputs
        st = a.variables[1 + i]
        a.variables.append(
            Variable(
                f"der({st.name})",
                Kind.DERIVATIVE,
                None,
                DERIVATIVE_UNIT[st.unit],
                f"time derivative of {st.name}",
                derivative_of=1 + i,
            )
        )
    names = [v.name for v in a.variables]
    if len(set(names)) != len(names):
        raise ValueError(
            f"scene {scene.name}: variable names repeat: {sorted({n for n in names if names.count(n) > 1})}"
        )
    return RigidBodyModel(
        scene=scene,
        variables=a.variables,
        nx=nx,
        nu=a.u.shape[0],
        np_=a.p.shape[0],
        ny=y.shape[0],
        functions=functions,
        checks=[(t, s) for t, _, s in a.checks],
        h_max_index=a.h_max_index,
        methods=scene.methods,
        default_method=scene.method,
    )


__all__ = ["BUILDERS", "Assembly", "Kind", "RigidBodyModel", "Variable", "build_model"]
