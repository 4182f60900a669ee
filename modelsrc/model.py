"""A scene -> the CasADi model of its FMU (functions + FMI variable metadata).

Only what the scene uses is built: a torque-free scene has no torque inputs and no
gravity parameters, and derived outputs not requested are not computed.

State x = (q[1..4], w_body[1..3]): unit quaternion body -> world (scalar first) and
angular velocity (rad/s, body frame). See docs/theory.md §6 for the assembly.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from . import rigid_body as rb
from .inertia import inertia_conditions, parallel_axis_shift
from .integrators import gauss_step, rk4_step, rk8_step, splitting_step
from .quaternion import euler_zxz, quat_derivative, rotation_matrix
from .methods import METHODS
from .scene import QUAT_NORM_TOL, Scene

# Kinds of variables, as the C layer sees them (its set/get rules depend on the kind).
INDEPENDENT, STATE, INPUT, PARAM_FIXED, PARAM_TUNABLE, OUTPUT, DERIVATIVE = range(7)


@dataclass
class Variable:
    """One FMI Float64 variable (scalar; arrays are flattened with 1-based names).
    derivative_of: for a state derivative, the value reference of its state."""

    name: str
    kind: int
    start: float | None
    unit: str | None
    description: str
    derivative_of: int | None = None


def _vec(name: str, n: int) -> list[str]:
    return [f"{name}[{i}]" for i in range(1, n + 1)]


@dataclass
class RigidBodyModel:
    """The model of one scene.

    variables: all FMI variables in value-reference order (vr = index), laid out as
    [time | states x | inputs u | parameters p | derived outputs y | derivatives dx],
    the same layout as the C layer's value buffer. functions: the CasADi functions whose C is
    generated (model_step, model_outputs, model_checks, model_project, model_rhs).
    checks: (text, strict) of each entry of model_checks' output (holds if > 0 / >= 0).
    methods: integrator names compiled in (functions model_step_<name>), in METHODS order.
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


def build_model(scene: Scene) -> RigidBodyModel:
    """Assemble the equations of rigid_body.py for a scene (docs/theory.md §6)."""
    variables: list[Variable] = [Variable("time", INDEPENDENT, None, "s", "simulation time")]

    # --- states (their start values are the scene's initial state; settable) ---
    q = ca.SX.sym("q", 4)
    w = ca.SX.sym("w", 3)
    x = ca.vertcat(q, w)
    for i, n in enumerate(_vec("q", 4)):
        variables.append(
            Variable(
                n,
                STATE,
                float(scene.q0[i]),
                None,
                f"orientation quaternion body->world, component {'wxyz'[i]} (scalar first)",
            )
        )
    for i, n in enumerate(_vec("w_body", 3)):
        variables.append(Variable(n, STATE, float(scene.w0[i]), "rad/s", f"angular velocity, body axis {i + 1}"))

    # --- inputs ---
    u_parts = []
    R = rotation_matrix(q)  # a rotation for any |q| (Model Exchange lets |q| drift)
    qn = ca.norm_2(q)
    tau = ca.SX.zeros(3)
    if scene.has("torque_body"):
        tb = ca.SX.sym("tau_body", 3)
        u_parts.append(tb)
        tau = tau + tb
        start = scene.inputs.get("tau_body", np.zeros(3))
        start = start[0, 1:] if start.ndim == 2 else start
        for i, n in enumerate(_vec("tau_body", 3)):
            variables.append(Variable(n, INPUT, float(start[i]), "N.m", f"applied torque, body axis {i + 1}"))
    if scene.has("torque_world"):
        tw = ca.SX.sym("tau_world", 3)
        u_parts.append(tw)
        tau = tau + rb.world_to_body_torque(R, tw)
        start = scene.inputs.get("tau_world", np.zeros(3))
        start = start[0, 1:] if start.ndim == 2 else start
        for i, n in enumerate(_vec("tau_world", 3)):
            variables.append(Variable(n, INPUT, float(start[i]), "N.m", f"applied torque, world axis {i + 1}"))
    u = ca.vertcat(*u_parts) if u_parts else ca.SX.zeros(0, 1)

    # --- parameters ---
    p_parts = []
    checks: list[tuple[str, object, bool]] = []
    if scene.principal:
        Ip = ca.SX.sym("I_principal", 3)
        p_parts.append(Ip)
        I_cm = ca.diag(Ip)
        for i, n in enumerate(_vec("I_principal", 3)):
            variables.append(
                Variable(
                    n,
                    PARAM_FIXED,
                    float(scene.inertia[i, i]),
                    "kg.m2",
                    f"principal moment of inertia about body axis {i + 1}, centre of mass",
                )
            )
        names = ["I_principal[1]", "0", "0", "0", "I_principal[2]", "0", "0", "0", "I_principal[3]"]
        checks += [c for c in inertia_conditions(I_cm, names) if "symmetric" not in c[0]]
    else:
        Iv = ca.SX.sym("I", 9)  # row major I[1,1], I[1,2], ..., I[3,3]
        p_parts.append(Iv)
        I_cm = ca.reshape(Iv, 3, 3).T
        names = [f"I[{i},{j}]" for i in range(1, 4) for j in range(1, 4)]
        for k, n in enumerate(names):
            variables.append(
                Variable(
                    n,
                    PARAM_FIXED,
                    float(scene.inertia.ravel()[k]),
                    "kg.m2",
                    f"inertia tensor entry {n[1:]} about the centre of mass, body frame",
                )
            )
        checks += inertia_conditions(I_cm, names)
    I = I_cm
    V = None
    if scene.has("gravity"):
        m = ca.SX.sym("mass")
        r_cm = ca.SX.sym("r_cm", 3)
        g = ca.SX.sym("g", 3)
        p_parts += [m, r_cm, g]
        variables.append(Variable("mass", PARAM_FIXED, scene.mass, "kg", "mass of the body"))
        for i, n in enumerate(_vec("r_cm", 3)):
            variables.append(
                Variable(n, PARAM_FIXED, float(scene.r_cm[i]), "m", f"pivot -> centre of mass, body axis {i + 1}")
            )
        for i, n in enumerate(_vec("g", 3)):
            variables.append(
                Variable(n, PARAM_FIXED, float(scene.g[i]), "m/s2", f"gravitational acceleration, world axis {i + 1}")
            )
        checks.append(("mass must be > 0", m, True))
        # Heavy top: rotation about the pivot, inertia shifted there (docs/theory.md §4.1)
        I = parallel_axis_shift(I_cm, m, r_cm)
        tau = tau + rb.gravity_torque(R, r_cm, m, g)
        V = rb.potential_energy(R, r_cm, m, g)
    tau_conservative = tau  # everything but friction: the splitting's kick
    c = None
    c_index = None  # position of c_friction in p, for the splittings' exact damping
    if scene.has("friction"):
        c = ca.SX.sym("c_friction")
        c_index = sum(part.shape[0] for part in p_parts)
        p_parts.append(c)
        variables.append(
            Variable(
                "c_friction",
                PARAM_FIXED,
                scene.c_friction,
                "N.m.s/rad",
                "viscous friction coefficient: torque -c*w_body",
            )
        )
        checks.append(("c_friction must be >= 0", c, False))
        tau = tau + rb.friction_torque(w, c)
    if "sensor" in scene.outputs:
        r_sensor = ca.SX.sym("r_sensor", 3)
        p_parts.append(r_sensor)
        for i, n in enumerate(_vec("r_sensor", 3)):
            variables.append(
                Variable(
                    n,
                    PARAM_FIXED,
                    float(scene.sensor_point[i]),
                    "m",
                    f"sensor point from the rotation point, body axis {i + 1}",
                )
            )
    h_max = ca.SX.sym("h_max")
    p_parts.append(h_max)
    h_max_index = len(variables)
    variables.append(
        Variable(
            "h_max",
            PARAM_TUNABLE,
            scene.h_max,
            "s",
            "maximum internal integrator step; each doStep takes ceil(H/h_max) equal substeps",
        )
    )
    checks.append(("h_max must be > 0", h_max, True))
    method = ca.SX.sym("method")  # the enumeration value of the selected method
    for split in [m_ for m_ in ("splitting", "exact_free") if m_ in scene.methods]:
        off = ca.fmax(ca.fmax(ca.fabs(I[0, 1]), ca.fabs(I[0, 2])), ca.fabs(I[1, 2]))
        checks.append(
            (
                f"method {split} needs principal axes about the rotation point: r_cm along one body axis",
                ca.if_else(method == METHODS[split].value, 1e-12 * (I[0, 0] + I[1, 1] + I[2, 2]) - off, 1),
                False,
            )
        )
    checks.append(
        (f"quaternion q must have unit norm (| |q| - 1 | <= {QUAT_NORM_TOL:g})", QUAT_NORM_TOL - ca.fabs(qn - 1), False)
    )
    p = ca.vertcat(*p_parts)

    # --- equations: Euler + quaternion kinematics (docs/theory.md §2, §1.2) ---
    if scene.has("prescribed_rate"):
        # held at a constant rate about a fixed axis: ω is constant in the body frame
        # (d/dt Rᵀ Ω = −ω × ω = 0); the torque doing it is an output (docs/theory.md §4.4)
        w_dot = ca.SX.zeros(3)
    else:
        w_dot = rb.euler_rhs(I, w, tau)
    xdot = ca.vertcat(quat_derivative(q, w), w_dot)
    rhs = ca.Function("model_rhs", [x, u, p], [xdot], ["x", "u", "p"], ["xdot"])
    # Time scales that size the automatic sub-steps (docs/theory.md §5.4): ||∂f/∂x||∞ >=
    # ρ(∂f/∂x) (1/s: spin, friction c/I, gravity) for stability, and |ω| (rad/s) for accuracy
    rate = ca.Function(
        "model_rate",
        [x, u, p],
        [ca.vertcat(ca.norm_inf(ca.jacobian(xdot, x)), ca.norm_2(w))],
        ["x", "u", "p"],
        ["rate"],
    )
    project = ca.Function("model_project", [x], [ca.vertcat(q / qn, w)], ["x"], ["x_projected"])

    # --- derived outputs, only those requested ---
    Ek = rb.kinetic_energy(I, w)
    Lb = rb.angular_momentum_body(I, w)
    derived = {
        "w_world": (R @ w, "rad/s", "angular velocity, world axis {}"),
        "euler_zxz": (euler_zxz(R), "rad", "z-x-z Euler angle {} (phi, theta, psi)"),
        "E_kin": (Ek, "J", "rotational kinetic energy"),
        "E_total": (Ek + V if V is not None else Ek, "J", "kinetic + potential energy (pivot reference)"),
        "L_world": (R @ Lb, "N.m.s", "angular momentum, world axis {}"),
        "L_body": (Lb, "N.m.s", "angular momentum, body axis {}"),
    }
    if "sensor" in scene.outputs:
        r_world = R @ r_sensor
        w_world = R @ w
        derived["sensor"] = (
            ca.vertcat(
                r_world, rb.point_velocity(w_world, r_world), rb.point_acceleration(w_world, R @ w_dot, r_world)
            ),
            None,
            None,
        )
    if "tau_bearing" in scene.outputs:
        derived["tau_bearing"] = (
            R @ rb.inverse_dynamics_torque(I, w, w_dot),
            "N.m",
            "torque the bearings supply to hold the rate, world axis {}",
        )
    y_parts = []
    for name in scene.outputs:
        if name not in derived:
            continue
        expr, unit, desc = derived[name]
        y_parts.append(expr)
        n = expr.shape[0]
        if name == "sensor":
            for base, u_, d_ in (
                ("sensor_r", "m", "position"),
                ("sensor_v", "m/s", "velocity"),
                ("sensor_a", "m/s2", "acceleration"),
            ):
                for i, vn in enumerate(_vec(base, 3)):
                    variables.append(Variable(vn, OUTPUT, None, u_, f"{d_} of the sensor point, world axis {i + 1}"))
        elif n == 1:
            variables.append(Variable(name, OUTPUT, None, unit, desc))
        else:
            for i, vn in enumerate(_vec(name, n)):
                variables.append(Variable(vn, OUTPUT, None, unit, desc.format(i + 1)))
    y = ca.vertcat(*y_parts) if y_parts else ca.SX.zeros(0, 1)
    outputs = ca.Function("model_outputs", [x, u, p], [y], ["x", "u", "p"], ["y"])
    # state derivatives (Model Exchange), their variables after the outputs
    for i in range(7):
        st = variables[1 + i]
        variables.append(
            Variable(
                f"der({st.name})",
                DERIVATIVE,
                None,
                "1/s" if i < 4 else "rad/s2",
                f"time derivative of {st.name}",
                derivative_of=1 + i,
            )
        )
    # Jacobian of (x, ẋ, y) w.r.t. (x, u) by CasADi's AD, dense column major: the FMU's
    # directional and adjoint derivatives (docs/fmi_layer.md)
    z = ca.vertcat(x, xdot, y)
    jac = ca.Function("model_jac", [x, u, p], [ca.densify(ca.jacobian(z, ca.vertcat(x, u)))], ["x", "u", "p"], ["J"])
    checks_fun = ca.Function(
        "model_checks", [x, p, method], [ca.vertcat(*[ch[1] for ch in checks])], ["x", "p", "method"], ["g"]
    )

    functions = {
        "model_outputs": outputs,
        "model_checks": checks_fun,
        "model_project": project,
        "model_rhs": rhs,
        "model_rate": rate,
        "model_jac": jac,
    }
    nu, np_ = u.shape[0], p.shape[0]
    torque_fun = ca.Function("torque", [q, u, p], [tau_conservative])
    I_fun = ca.Function("I_diag", [p], [ca.diag(I)])
    friction = (lambda p_: p_[c_index]) if c is not None else (lambda p_: None)

    def split(name: str, exact: bool) -> ca.Function:
        return splitting_step(
            project, 7, nu, np_, torque_fun, lambda p_: ca.vertsplit(I_fun(p_)), friction, name, exact=exact
        )

    builders = {
        "rk4": lambda n: rk4_step(rhs, project, n),
        "rk8": lambda n: rk8_step(rhs, project, n),
        "implicit_midpoint": lambda n: gauss_step(rhs, project, 1, n),
        "gauss4": lambda n: gauss_step(rhs, project, 2, n),
        "gauss6": lambda n: gauss_step(rhs, project, 3, n),
        "splitting": lambda n: split(n, exact=False),
        "exact_free": lambda n: split(n, exact=True),
    }
    for m in scene.methods:
        functions[f"model_step_{m}"] = builders[m](f"model_step_{m}")
    return RigidBodyModel(
        scene=scene,
        variables=variables,
        nx=7,
        nu=nu,
        np_=np_,
        ny=y.shape[0],
        functions=functions,
        checks=[(ch[0], ch[2]) for ch in checks],
        h_max_index=h_max_index,
        methods=scene.methods,
        default_method=scene.method,
    )
