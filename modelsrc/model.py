"""Assembles a scene's CasADi model: the equations of rigid_body.py, the FMI variables and the generated functions.

Only what the scene uses is built: a torque-free scene has no torque inputs and no
gravity parameters, and derived outputs not requested are not computed. The body's
builders are here (its states q, w_body, its inertia, the parameter ranges, the step
controls and report); each feature's (modelsrc/features/, found by modelsrc.registry)
add their symbols, variables, torques and checks to an `Assembly`; `build_model` runs
them all in value-reference order (`BUILDERS`, docs/features.md).

State x = (q[1..4], w_body[1..3]): unit quaternion body -> world (scalar first) and
angular velocity (rad/s, body frame); a free body adds (x_cm, v_cm), a moving pivot
(x_pivot, v_pivot) (m, m/s, world). See docs/theory.md §6 for the assembly.

What depends on the parameters only (the inertia about the rotation point and its
inverse, the weight m g, 1/m, the splitting's axis order) is a derived parameter d:
`Assembly.derive` gives it a symbol that the equations use, and the generated
`model_derived` evaluates it once per parameter change, not in every right-hand side
(docs/theory.md §6).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from . import registry
from . import rigid_body as rb
from .assembly import Assembly
from .feature import Phase
from .inertia import inertia_conditions
from .methods import DEFAULT_TOLERANCE, METHODS, WORK_LIMIT, WORK_LIMIT_MAX
from .model_functions import derived_outputs, model_functions, step_name
from .nominals import state_nominals
from .quaternion import quat_derivative
from .scene import QUAT_NORM_TOL, Scene
from .scene_reader import PARAM_MAX, POSITIVE_MIN
from .variables import Kind, Variable, vector_names


@dataclass
class RigidBodyModel:
    """The model of one scene.

    variables: all FMI variables in value-reference order (vr = index), laid out as
    [time | states x | inputs u | parameters p | step report l | derived outputs y |
    derivatives dx], the same layout as the C layer's value buffer. functions: the CasADi
    functions whose C is generated (model_step_<method>, model_outputs, model_checks,
    model_project, model_rhs, model_rate, model_jac, model_derived, model_output_rates).
    checks: (text, strict) of each entry of model_checks' output (holds if > 0 / >= 0).
    methods: integrator names compiled in, in METHODS order. nd: number of derived
    parameters; nl: of step-report variables. principal_test: the entries of d that must all
    be 0 for the steps model_step_<m>_principal (model_functions.principal_steps), () when
    there are none.
    """

    scene: Scene
    variables: list[Variable]
    nx: int
    nu: int
    np_: int
    nl: int
    ny: int
    nd: int
    functions: dict[str, ca.Function]
    checks: list[tuple[str, bool]]
    h_max_index: int
    methods: tuple[str, ...]
    default_method: str
    principal_test: tuple[int, ...] = ()

    @property
    def offsets(self) -> dict[str, int]:
        """Buffer offsets of the six blocks (x, u, p, l, y, dx)."""
        p = 1 + self.nx + self.nu
        y = p + self.np_ + self.nl
        return {"x": 1, "u": 1 + self.nx, "p": p, "l": p + self.np_, "y": y, "dx": y + self.ny}

    def vr(self, name: str) -> int:
        """Value reference of a variable by name."""
        for i, v in enumerate(self.variables):
            if v.name == name:
                return i
        raise KeyError(name)


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


def add_inertia(a: Assembly) -> None:
    """Principal moments (3 parameters) or the full tensor (9), about the centre of mass,
    or about the pivot when the scene says so (`inertia_about = "pivot"`; then the heavy top
    checks the tensor about the centre of mass it implies), with the validity conditions
    of docs/theory.md §3.4 as checks."""
    sc = a.scene
    about_pivot = sc.pivot_inertia is not None
    tensor = np.asarray(sc.pivot_inertia if sc.pivot_inertia is not None else sc.inertia)
    where = "pivot" if about_pivot else "centre of mass"
    if sc.principal:
        Ip = ca.SX.sym("I_principal", 3)
        a.parameter(
            Ip,
            vector_names("I_principal", 3),
            np.diag(tensor),
            "kg.m2",
            [f"principal moment of inertia about body axis {i}, {where}" for i in (1, 2, 3)],
        )
        a.inertia = ca.diag(Ip)
        names = ["I_principal[1]", "0", "0", "0", "I_principal[2]", "0", "0", "0", "I_principal[3]"]
        conditions = [c for c in inertia_conditions(a.inertia, names) if "symmetric" not in c[0]]
    else:
        Iv = ca.SX.sym("I", 9)  # row major I[1,1], I[1,2], ..., I[3,3]
        names = [f"I[{i},{j}]" for i in range(1, 4) for j in range(1, 4)]
        a.parameter(
            Iv,
            names,
            tensor.ravel(),
            "kg.m2",
            [f"inertia tensor entry {n[1:]} about the {where}, body frame" for n in names],
        )
        a.inertia = ca.reshape(Iv, 3, 3).T
        conditions = inertia_conditions(a.inertia, names)
    if about_pivot:  # the tensor about the pivot: a valid tensor, and the heavy top checks its I_cm
        a.checks += [(f"{t} (about the pivot)", e, strict) for t, e, strict in conditions]
        return
    a.inertia_cm = a.inertia
    a.checks += conditions


# The range of the physical parameters (docs/user_guide.md §2.3, Parameter ranges): every
# parameter |p| <= PARAM_MAX (modelsrc.scene_reader), masses and the inertia's diagonal >= POSITIVE_MIN. The outputs
# are products of at most three such factors and the states (E = m g.r, w.I w / 2, v = w x r)
# and the right-hand side divides by m and I, so with each factor within 1e-100..1e100 no
# product of the parameters alone exceeds 1e300 < DBL_MAX = 1.8e308 (issue 23.11: mass 1e-310,
# I_1 = 1e-310, g = 1e300, r_sensor = 1.7e308 passed the checks and made outputs non-finite).
# What the states add (a spin grown without bound) the FMU's check of its outputs after
# initialisation and each doStep refuses (fmu/c/rbfmu_core.c, rb_outputs_finite).
POSITIVE_PARAMETERS = ("mass", "I_principal[1]", "I_principal[2]", "I_principal[3]", "I[1,1]", "I[2,2]", "I[3,3]")


def add_parameter_ranges(a: Assembly) -> None:
    """The range checks of the physical parameters (all parameters declared so far):
    |p| <= PARAM_MAX, and >= POSITIVE_MIN for masses, the inertia's diagonal and the
    features' `Assembly.positive_parameters` (a rotor's axial inertia J)."""
    params = [v for v in a.variables if v.kind in (Kind.PARAM_FIXED, Kind.PARAM_TUNABLE)]
    p = a.params
    assert len(params) == p.shape[0], "every parameter has one entry of p"
    for i, v in enumerate(params):
        unit = f" {v.unit}" if v.unit else ""
        if v.name in POSITIVE_PARAMETERS or v.name in a.positive_parameters:
            a.checks.append(
                (
                    f"{v.name} must be in [{POSITIVE_MIN:g}, {PARAM_MAX:g}]{unit} (the range that keeps the outputs "
                    "finite)",
                    ca.fmin(p[i] - POSITIVE_MIN, PARAM_MAX - p[i]),
                    False,
                )
            )
        else:
            a.checks.append(
                (
                    f"|{v.name}| must be <= {PARAM_MAX:g}{unit} (the range that keeps the outputs finite)",
                    PARAM_MAX - ca.fabs(p[i]),
                    False,
                )
            )


def add_step_controls(a: Assembly) -> None:
    """tolerance, h_max and work_limit (tunable) and the checks that depend on the method
    and the state (docs/theory.md §5.4, §5.5)."""
    tolerance = ca.SX.sym("tolerance")
    a.parameter(
        tolerance,
        ["tolerance"],
        [a.scene.tolerance],
        "1/s",
        [
            "relative error per second of simulated time that the error-controlled internal steps keep (floors: "
            "the states' nominal values); 0: fixed steps (h_max, the method's limits). Methods without an error "
            f"estimate always take fixed steps (default {DEFAULT_TOLERANCE:g})"
        ],
        Kind.PARAM_TUNABLE,
    )
    a.checks.append(("tolerance must be >= 0", tolerance, False))
    h_max = ca.SX.sym("h_max")
    a.h_max_index = len(a.variables)
    a.parameter(
        h_max,
        ["h_max"],
        [a.scene.h_max],
        "s",
        [
            "largest internal step (0: no cap). Fixed stepping (tolerance = 0) takes ceil(H/h_max) equal steps "
            "per doStep, more if the method's stability or rotation limit needs them; error control never steps "
            "beyond it"
        ],
        Kind.PARAM_TUNABLE,
    )
    a.checks.append(("h_max must be >= 0 (0: no cap)", h_max, False))
    work_limit = ca.SX.sym("work_limit")
    a.parameter(
        work_limit,
        ["work_limit"],
        [WORK_LIMIT],
        None,
        [
            "most work one doStep may do, in right-hand-side evaluations (one internal step costs "
            + ", ".join(f"{m} {METHODS[m].cost:g}" for m in a.scene.methods)
            + "; retries count); a doStep that would need more is refused before it starts; at most "
            + f"{WORK_LIMIT_MAX:g}"
        ],
        Kind.PARAM_TUNABLE,
    )
    a.checks.append(("work_limit must be > 0", work_limit, True))
    a.checks.append(
        (
            f"work_limit must be <= {WORK_LIMIT_MAX:g} (allowed: 0 < work_limit <= {WORK_LIMIT_MAX:g})",
            WORK_LIMIT_MAX - work_limit,
            False,
        )
    )
    off = ca.fmax(ca.fmax(ca.fabs(a.inertia[0, 1]), ca.fabs(a.inertia[0, 2])), ca.fabs(a.inertia[1, 2]))
    for name in a.scene.methods:
        if METHODS[name].needs_principal:
            a.checks.append(
                (
                    f"method {name} needs principal axes about the rotation point: r_cm along one body axis",
                    ca.if_else(a.method == METHODS[name].value, 1e-12 * ca.trace(a.inertia) - off, 1),
                    False,
                )
            )
    qn = ca.norm_2(a.quaternion)
    a.checks.append(
        (f"quaternion q must have unit norm (| |q| - 1 | <= {QUAT_NORM_TOL:g})", QUAT_NORM_TOL - ca.fabs(qn - 1), False)
    )


# The step report (Kind.LOCAL): what the last doStep did, and the error control's memory.
STEP_REPORT = (
    ("internal_steps", None, "internal steps the last doStep took (accepted)"),
    ("rejected_steps", None, "internal steps the last doStep rejected and redid smaller (error estimate above the "
                             "tolerance, Newton not converged, or a non-finite state), whole-step retries included"),
    ("h_last", "s", "size of the last internal step of the last doStep"),
    ("h_next", "s", "step the error control proposes for the next internal step (0: none yet; fixed stepping "
                    "leaves it 0); part of the FMU state, so a restored state repeats a doStep exactly"),
    ("tolerance_effective", "1/s", "the tolerance the last doStep's error control held: `tolerance`, or more where "
                                   "the error estimate could not resolve it (round-off, docs/theory.md §5.5); 0 under "
                                   "fixed stepping"),
    ("tolerance_floor", "1/s", "the lowest tolerance the error estimate has shown it resolves in this run (its "
                               "round-off, docs/theory.md §5.5; 0: none found); the error control holds "
                               "max(tolerance, tolerance_floor); part of the FMU state"),
)  # fmt: skip


def add_step_report(a: Assembly) -> None:
    """The step report: local variables, set by doStep only (docs/fmi_layer.md)."""
    for name, unit, desc in STEP_REPORT:
        a.variables.append(Variable(name, Kind.LOCAL, None, unit, desc))


def _features(phase: Phase) -> tuple[Callable[[Assembly], None], ...]:
    return tuple(b.build for b in registry.builders(phase))


# Every builder in value-reference order: the body's states, the features' states and
# inputs, the body's inertia, the features' parameters, the body's parameter ranges, step
# controls and step report (docs/theory.md §6, docs/features.md).
BUILDERS: tuple[Callable[[Assembly], None], ...] = (
    add_states,
    *_features(Phase.STATES),
    *_features(Phase.INPUTS),
    add_inertia,
    *_features(Phase.PARAMETERS),
    add_parameter_ranges,
    add_step_controls,
    add_step_report,
)


# unit of a state -> unit of its time derivative (q is dimensionless)
DERIVATIVE_UNIT = {None: "1/s", "rad/s": "rad/s2", "m": "m/s", "m/s": "m/s2", "rad": "rad/s"}


def euler_acceleration(a: Assembly) -> ca.SX:
    """ω̇ (rad/s², body) of Euler's equations, where no feature replaces them; on principal
    axes (a diagonal tensor) in the form of `rigid_body.principal_euler_rhs` (`finish_inertia`
    made it)."""
    if a.inertia.sparsity().is_diag() and a.omega_dot_principal is not None:
        return a.omega_dot_principal
    return rb.euler_rhs(a.inertia, a.omega, a.torque, a.inertia_inv)


def principal_rates(a: Assembly, moments: list, inv: ca.SX) -> ca.SX:
    """ω̇ on principal axes (rigid_body.principal_euler_rhs) with the derived coefficients
    (I_2 − I_3)/I_1 ..., c/I_i and the torques kept out of the torque on principal axes (in
    an orbit the gravity gradient's 3 n² (I_3 − I_2)/I_1, cyclic) (docs/theory.md §2, §4.3,
    §9.2). moments: the principal moments as expressions of p; inv: the derived 1/I_i (3
    symbols)."""
    recip = [1 / m for m in moments]
    coeff = rb.principal_coefficients(moments, recip)
    k = a.derive("euler_coeff", coeff)
    c = a.friction_coefficient
    damping = None if c is None else a.derive("friction_rate", ca.vertcat(*[c * r for r in recip]))
    w_dot = rb.principal_euler_rhs(a.omega, a.torque_without_friction(), inv, k, damping)
    for term in a.principal_terms:
        w_dot = w_dot + term.acceleration(coeff, "")
    return w_dot


def finish_inertia(a: Assembly, euler: bool) -> None:
    """The inertia about the rotation point and its inverse become derived parameters
    (computed once per parameter change): diagonal ones as 3 numbers, full ones as 9;
    with Euler's equations (`euler`: no feature replaces them) their form on principal axes."""
    moments = ca.diag(a.inertia)  # about the rotation point, as expressions of p
    I_expr = a.inertia
    if "splitting" in a.scene.methods:  # its axes in the order of their moments (rigid_body.sorted_axis_order)
        order = rb.sorted_axis_order(ca.vertsplit(moments))
        a.split_axes = a.derive("split_axes", ca.vertcat(*[ca.vertcat(*e) for e in order[:3]], *order[3:]))
    if a.inertia.sparsity().is_diag():
        Id = a.derive("I_rot", moments)
        a.inertia = ca.diag(Id)
        inv = a.derive("I_rot_inv", 1 / moments)
        a.inertia_inv = ca.diag(inv)
        if euler:
            a.omega_dot_principal = principal_rates(a, ca.vertsplit(moments), inv)
    else:
        # a tensor full as an expression (r_cm off the axes is allowed) may still be diagonal
        # for the parameters set: its off-diagonal entries in d (column-major) let the FMU
        # switch to steps without them (model_functions.principal_steps)
        n0 = a.derived_params.shape[0]
        a.inertia, a.inertia_inv = (
            a.derive("I_rot", ca.densify(a.inertia)),
            a.derive("I_rot_inv", ca.inv(ca.densify(a.inertia))),
        )
        a.off_diagonal = [n0 + block + i + 3 * j for block in (0, 9) for j in range(3) for i in range(3) if i != j]
        if euler:  # for the steps taken while the tensor is diagonal as set (model_functions.principal_steps)
            a.omega_dot_principal = principal_rates(a, [I_expr[i, i] for i in range(3)], ca.diag(a.inertia_inv))


def build_model(scene: Scene) -> RigidBodyModel:
    """Assemble the equations of rigid_body.py for a scene (docs/theory.md §6)."""
    a = Assembly(scene)
    a.energy_terms = [f.energy for f in registry.FEATURE_UNITS if f.energy is not None]
    a.momentum_terms = [f.momentum for f in registry.FEATURE_UNITS if f.momentum is not None]
    for builder in BUILDERS:
        builder(a)
    a.checks = [(t, a.without_derived(e), st) for t, e, st in a.checks]
    replaced = registry.angular_acceleration(scene)  # the gyrostat's (§8.1, §8.5), a prescribed rate's (§4.4)
    finish_inertia(a, euler=replaced is None)
    for feature in registry.FEATURE_UNITS:
        if feature.finish is not None:
            feature.finish(a)  # the reference point's acceleration (§7)
    w_dot = euler_acceleration(a) if replaced is None else replaced.omega_dot(a)

    def state_rates(w_dot: ca.SX) -> ca.SX:
        # q̇, ω̇, then each state part's rate: ẋ = v, v̇ = a (§7.1, §7.3), Ω̇ (§8.1), θ̇ = n (§9.1)
        rates = []
        for part in a.state_parts:
            assert part.rate is not None, f"state part {part.name} without its rate"
            rates.append(part.rate)
        return ca.vertcat(quat_derivative(a.quaternion, a.omega), w_dot, *rates)

    xdot = state_rates(w_dot)
    y = derived_outputs(a, w_dot)
    # a full tensor's steps for the parameters that make it diagonal (principal_steps)
    xdot_principal = (
        state_rates(a.omega_dot_principal) if a.off_diagonal and a.omega_dot_principal is not None else None
    )
    functions = model_functions(a, xdot, y, xdot_principal)
    nx = a.states.shape[0]
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
    nominals = state_nominals(scene)
    for v in a.variables:
        if v.kind == Kind.STATE:
            v.nominal = nominals[v.name.split("[")[0]]
    names = [v.name for v in a.variables]
    if len(set(names)) != len(names):
        raise ValueError(
            f"scene {scene.name}: variable names repeat: {sorted({n for n in names if names.count(n) > 1})}"
        )
    return RigidBodyModel(
        scene=scene,
        variables=a.variables,
        nx=nx,
        nu=a.inputs.shape[0],
        np_=a.params.shape[0],
        nl=len(STEP_REPORT),
        ny=y.shape[0],
        nd=a.derived_params.shape[0],
        functions=functions,
        checks=[(t, s) for t, _, s in a.checks],
        h_max_index=a.h_max_index,
        methods=scene.methods,
        default_method=scene.method,
        # the entries the FMU tests to take the steps for a diagonal inertia, where generated
        principal_test=tuple(a.off_diagonal)
        if any(step_name(m, principal=True) in functions for m in scene.methods)
        else (),
    )


__all__ = ["BUILDERS", "Kind", "RigidBodyModel", "Variable", "build_model"]
