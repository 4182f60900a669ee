"""The generated functions of a scene's model: right-hand side, outputs, checks, Jacobian and integrator steps.

`model.build_model` assembles the equations feature by feature (an `Assembly`); this
module turns them into the CasADi Functions whose C is generated (fmu/build/codegen.py) and
adds the outputs: the body's, those the features always have and those the scene asks
for (modelsrc.registry). Every function of the state takes the derived parameters d
(`model_derived(p)`, evaluated by the FMU once per parameter change) after p.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import casadi as ca
import numpy as np

from . import registry
from . import rigid_body as rb
from .assembly import Assembly
from .feature import REQUESTED_RANK, OutputContext, OutputValue, ScalarOutput
from .integrators import (
    FIXED_VARIANTS,
    Clock,
    ErrorNorm,
    constants_name,
    gauss_step,
    rk4_step,
    rk8_step,
    splitting_step,
    step_constants,
)
from .nominals import state_nominals
from .quaternion import euler_zxz, normalized
from .shared_subexpressions import merged
from .variables import Kind, Variable, vector_names


def derived_outputs(a: Assembly, w_dot: ca.SX) -> ca.SX:
    """The outputs y: those the features always have (before or after the requested ones,
    by their ranks) and the ones the scene requests, in the order of scene.OUTPUTS; their
    variables are appended to the assembly."""
    # with rotors: E and L of the whole gyrostat (docs/theory.md §8.2); 0 without
    Ek = rb.kinetic_energy(a.inertia, a.omega) + a.internal_energy(a.omega)
    Lb = rb.angular_momentum_body(a.inertia, a.omega) + a.internal_momentum()
    w_world = a.rotation_matrix @ a.omega
    derived = {
        "w_world": OutputValue(w_world, "rad/s", "angular velocity, world axis {}"),
        "euler_zxz": OutputValue(euler_zxz(a.rotation_matrix), "rad", "z-x-z Euler angle {} (phi, theta, psi)"),
        "E_kin": OutputValue(Ek, "J", "rotational kinetic energy"),
        "E_total": OutputValue(
            Ek + a.potential if a.potential is not None else Ek, "J", "kinetic + potential energy (pivot reference)"
        ),
        "L_world": OutputValue(a.rotation_matrix @ Lb, "N.m.s", "angular momentum, world axis {}"),
        "L_body": OutputValue(Lb, "N.m.s", "angular momentum, body axis {}"),
    }
    ctx = OutputContext(w_dot, w_world)
    for feature in registry.FEATURE_UNITS:  # a moving reference point's (§7), the sensor's, the bearing torque
        if feature.requested is not None:
            derived.update(feature.requested(a, ctx))
    always = sorted((f.always for f in registry.FEATURE_UNITS if f.always is not None), key=lambda o: o.rank)
    blocks: list[tuple[int, list[ScalarOutput]]] = [(o.rank, o.outputs(a, w_dot)) for o in always]
    parts: list[ca.SX] = []
    # the features' (the rotors', the orbit's, §9.4), before the requested ones
    for rank, outputs in blocks:
        if rank < REQUESTED_RANK:
            _add_scalars(a, parts, outputs)
    for name in a.scene.outputs:
        if name not in derived:
            continue  # the states q, w_body are outputs already
        value = derived[name]
        parts.append(value.expr)
        if value.variables is not None:
            a.variables += value.variables
        elif value.expr.shape[0] == 1:
            a.variables.append(Variable(name, Kind.OUTPUT, None, value.unit, value.description))
        else:
            n = value.expr.shape[0]
            descs = [value.description.format(i) for i in range(1, n + 1)]
            a.add(vector_names(name, n), Kind.OUTPUT, [None] * n, value.unit, descs)
    for rank, outputs in blocks:  # after them (the central field's r_orbit, L_total, §9.7)
        if rank > REQUESTED_RANK:
            _add_scalars(a, parts, outputs)
    return ca.vertcat(*parts) if parts else ca.SX.zeros(0, 1)


def _add_scalars(a: Assembly, parts: list[ca.SX], outputs: list[ScalarOutput]) -> None:
    for name, expr, unit, desc in outputs:
        parts.append(expr)
        a.variables.append(Variable(name, Kind.OUTPUT, None, unit, desc))


def largest_magnitude(m: ca.SX, depth: int = 64) -> ca.SX:
    """max |m_ij| over m's nonzeros (0 for none): what CasADi's norm_inf of a matrix computes
    (the ∞-norm of its entries, not the induced row-sum norm), in C without a call per entry.
    norm_inf takes the libm fmax of every nonzero, repeated entries included (30 calls, 150
    instructions, in free_asymmetric's model_rate, evaluated once per doStep: issue 35); this
    takes each distinct entry once (structurally equal expressions up to `depth`, which
    evaluate alike) and compares with `<`, which CasADi writes inline. The same value bit for
    bit: |m_ij| >= 0, the running maximum is never NaN, and a NaN entry is passed over as
    fmax passes it over (tests/physics/test_rate_norm.py)."""
    distinct: list[ca.SX] = []
    for k in range(m.nnz()):
        e = m.nz[k]
        if not any(ca.is_equal(e, seen, depth) for seen in distinct):
            distinct.append(e)
    largest = ca.SX(0.0)
    for e in distinct:
        magnitude = ca.fabs(e)
        largest = ca.if_else(largest < magnitude, magnitude, largest)
    return largest


def induced_inf_norm(m: ca.SX) -> ca.SX:
    """‖m‖∞ = max_i Σ_j |m_ij|, the norm the ∞-vector norm induces (largest row sum of
    magnitudes; 0 for no nonzeros): an upper bound of m's spectral radius, as every induced
    norm is (m v = λ v gives |λ| ‖v‖ = ‖m v‖ ≤ ‖m‖ ‖v‖), which the largest entry alone is not
    (docs/theory.md §5.4: 3× below it for friction on an inertia skewed about the pivot).
    The row sums' maximum is taken by largest_magnitude (no fmax calls; a NaN row passed over)."""
    return largest_magnitude(ca.sum2(ca.fabs(m)))


def model_functions(a: Assembly, xdot: ca.SX, y: ca.SX, xdot_principal: ca.SX | None = None) -> dict[str, ca.Function]:
    """rhs, rate, project, outputs, Jacobian, checks, derived parameters, output
    derivatives and one step function per method; xdot_principal: the right-hand side on
    principal axes for the steps of a full tensor diagonal as set (`principal_steps`)."""
    x, u, p, d = a.states, a.inputs, a.params, a.derived_params
    xdot_open = xdot
    if a.clock is not None:  # sin θ and cos θ for their symbols but in the fixed steps (`clock_of`)
        xdot, y = close_clock(a, xdot), close_clock(a, y)
    rhs = ca.Function("model_rhs", [x, u, p, d], [xdot], ["x", "u", "p", "d"], ["xdot"])
    # Time scales that size the automatic sub-steps (docs/theory.md §5.4): the induced norm
    # ‖∂f/∂x‖∞ = max_i Σ_j |∂f_i/∂x_j|, an upper bound of the spectral radius (1/s: spin,
    # friction c/I, gravity), for stability, and |ω| (rad/s) for accuracy.
    # Over the rotation (q, ω, and the state parts that couple with it: the rotor rates Ω, §8,
    # the orbit angle, on which the gravity-gradient torque depends, §9) only: positions and
    # velocities of the reference point never act back on it, so ∂f/∂x is block triangular
    # and its other eigenvalues are 0 (§7.4)
    rows = list(range(7))
    for part, offset in zip(a.state_parts, state_offsets(a)):
        if part.rotational:
            rows += list(range(offset, offset + part.symbol.shape[0]))
    rot = ca.vertcat(a.quaternion, a.omega, *[part.symbol for part in a.state_parts if part.rotational])
    jac_rot = ca.jacobian(xdot[rows], rot)
    if a.rates_in_nominal_units:  # slow turning in an orbit (§9.1, §9.7)
        jac_rot = orbit_scaled_jacobian(a, jac_rot)
    stability = induced_inf_norm(jac_rot)
    orbit = translation_rate(a, xdot)
    if orbit is not None:  # the larger of the two blocks' bounds (docs/theory.md §5.4)
        stability = ca.if_else(stability < orbit, orbit, stability)
    rate_expr = ca.vertcat(stability, ca.norm_2(a.omega))
    rate = ca.Function("model_rate", [x, u, p, d], [rate_expr], ["x", "u", "p", "d"], ["rate"])
    # the rate and f at the end of a fixed-step doStep in one call: f there is the next
    # doStep's k1 while nothing is set in between (fmu/c/rbfmu_step.c, docs/fmi_layer.md). The
    # same expressions as model_rate's and model_rhs's: the same values bit for bit
    rate_rhs = ca.Function("model_rate_rhs", [x, u, p, d], [rate_expr, xdot], ["x", "u", "p", "d"], ["rate", "xdot"])
    parts = [part.symbol for part in a.state_parts]
    project = ca.Function(
        "model_project", [x], [ca.vertcat(normalized(a.quaternion), a.omega, *parts)], ["x"], ["x_projected"]
    )
    outputs = ca.Function("model_outputs", [x, u, p, d], [y], ["x", "u", "p", "d"], ["y"])
    # Jacobian of (x, ẋ, y) w.r.t. (x, u) by CasADi's AD, dense column major: the FMU's
    # directional and adjoint derivatives (docs/fmi_layer.md)
    J = ca.densify(ca.jacobian(ca.vertcat(x, xdot, y), ca.vertcat(x, u)))
    jac = ca.Function("model_jac", [x, u, p, d], [J], ["x", "u", "p", "d"], ["J"])
    checks = ca.Function(
        "model_checks", [x, p, a.method], [ca.vertcat(*[c[1] for c in a.checks])], ["x", "p", "method"], ["g"]
    )
    derived = ca.Function("model_derived", [p], [a.derived_values], ["p"], ["d"])
    functions = {
        "model_outputs": outputs,
        "model_checks": checks,
        "model_project": project,
        "model_rhs": rhs,
        "model_rate": rate,
        "model_rate_rhs": rate_rhs,
        "model_jac": jac,
        "model_derived": derived,
        "model_output_rates": output_rates(a, xdot, y),
    }
    clock = clock_of(a, xdot_open)
    functions.update(method_steps(a, a.scene.methods, rhs, project, principal=False, clock=clock))
    functions.update(principal_steps(a, xdot_open if xdot_principal is None else xdot_principal, derived, project))
    if clock is not None:
        for m in a.scene.methods:
            if m in CLOCK_METHODS:
                functions[constants_name(m)] = step_constants(clock, m, p.shape[0], d.shape[0])
    # the functions the FMU calls outside the steps, each copy of a term evaluated once (the
    # steps merge theirs when they are built: integrators._function)
    for name in FUNCTIONS_MERGED:
        functions[name] = merged(functions[name])
    return functions


# The generated functions whose repeated subexpressions are merged (shared_subexpressions.merged):
# the end rate of every fixed-step doStep, the outputs of every Get, the Jacobian of every
# directional derivative, the right-hand side of Model Exchange, the output derivatives.
FUNCTIONS_MERGED = ("model_rhs", "model_rate", "model_rate_rhs", "model_outputs", "model_jac", "model_output_rates")


# The methods whose fixed steps take a clock's angles by angle addition (integrators.Clock):
# the explicit Runge-Kutta steps. The Gauss steps' stages are implicit (their angles are
# unknowns of the Newton solve), the splittings are refused in an orbit.
CLOCK_METHODS = ("rk4", "rk8")


def close_clock(a: Assembly, expr: ca.SX) -> ca.SX:
    """expr with sin θ and cos θ of the clock state in place of their symbols (Assembly.clock)."""
    assert a.clock is not None
    th, _, s, c = a.clock
    return ca.substitute(expr, ca.vertcat(s, c), ca.vertcat(ca.sin(th), ca.cos(th)))


def clock_of(a: Assembly, xdot_open: ca.SX) -> Clock | None:
    """The model's clock for the integrators (None without one): θ's index in x, its rate
    n(p, d), and the right-hand side xdot_open with (sin θ, cos θ) an argument."""
    if a.clock is None:
        return None
    th, n, s, c = a.clock
    x, u, p, d = a.states, a.inputs, a.params, a.derived_params
    index = next(i for i in range(x.shape[0]) if ca.is_equal(x[i], th))
    rate = ca.Function("clock_rate", [p, d], [n], ["p", "d"], ["n"])
    sc = ca.vertcat(s, c)
    rhs = ca.Function("model_rhs_clock", [x, u, p, d, sc], [xdot_open], ["x", "u", "p", "d", "sc"], ["xdot"])
    return Clock(index, rate, rhs)


def translation_rate(a: Assembly, xdot: ca.SX) -> ca.SX | None:
    """√‖∂v̇/∂x‖∞ (1/s), a bound of the spectral radius of the reference point's block ẋ = v,
    v̇ = a(x) (its eigenvalues λ have λ² an eigenvalue of ∂v̇/∂x); None where v̇ does not depend
    on x (uniform gravity, forces, a shaken pivot: the block's eigenvalues are 0). The central
    field's (§9.7): ∂v̇/∂x = μ/r³ (3 r̂r̂ᵀ − 1), eigenvalues ±√2 n and ±i n, n = √(μ/r³), which
    the rotation block's norm does not see (a body at rest in orbit has no rotation rate)."""
    if a.position is None or a.velocity is None:
        return None
    k = next(i for part, i in zip(a.state_parts, state_offsets(a)) if part.symbol is a.velocity)
    v_dot = xdot[k : k + 3]
    gradient = ca.jacobian(v_dot, a.position)
    if gradient.nnz() == 0:
        return None
    # λ² ∈ eig(∂v̇/∂x) needs v̇ free of v (no drag: true of every feature, checked here)
    assert ca.jacobian(v_dot, a.velocity).nnz() == 0, "v̇ depends on v: the block bound does not hold"
    return ca.sqrt(induced_inf_norm(gradient))


def state_offsets(a: Assembly) -> list[int]:
    """The offset in x of each state part (after q and ω, 7 entries)."""
    offsets, k = [], 7
    for part in a.state_parts:
        offsets.append(k)
        k += part.symbol.shape[0]
    return offsets


def orbit_scaled_jacobian(a: Assembly, jac: ca.SX) -> ca.SX:
    """D⁻¹ J D, D the nominals of (q, ω, Ω, θ) (modelsrc.nominals): the same eigenvalues, so
    its norm still bounds the spectral radius, but without the unit mix of ∂q̇/∂ω = ½ q (order 1
    whatever the spin): a body in orbit turns at n ~ 1e-3 rad/s, and the unscaled norm ~ 1 1/s
    would cap its steps at a few seconds where the dynamics' own time scale is 1/n (§9.1)."""
    nominal = state_nominals(a.scene)
    scale = [1.0] * 4 + [nominal["w_body"]] * 3
    for part in a.state_parts:
        if part.rotational:
            scale += [nominal[part.name]] * part.symbol.shape[0]
    S = np.array(scale)
    return jac * ca.DM(S[None, :] / S[:, None])


def step_name(method: str, fixed: bool = False, principal: bool = False) -> str:
    """The name of a generated step function, the one rule for it: model_step_<method>;
    fixed True: the step fixed stepping calls, model_step_<method>_fixed for the
    FIXED_VARIANTS (without the error estimate), else the same step; principal True: the
    variant for a diagonal inertia (principal_steps), suffix _principal."""
    name = f"model_step_{method}" + ("_fixed" if fixed and method in FIXED_VARIANTS else "")
    return name + ("_principal" if principal else "")


def method_steps(
    a: Assembly,
    methods: Sequence[str],
    rhs: ca.Function,
    project: ca.Function,
    principal: bool,
    clock: Clock | None = None,
) -> dict[str, ca.Function]:
    """step_name -> step Function for each method, with and (FIXED_VARIANTS) without its
    error estimate, from the right-hand side rhs (and the clock the fixed explicit steps
    take their angles from, `clock_of`)."""
    steps = step_builders(a, rhs, project, clock)
    out = {}
    for m in methods:
        out[step_name(m, principal=principal)] = steps[m](step_name(m, principal=principal))
        if m in FIXED_VARIANTS:
            name = step_name(m, fixed=True, principal=principal)
            out[name] = steps[m](name, estimate=False)
    return out


# The methods that get steps of their own for an inertia about the rotation point that is
# diagonal as set although it is full as an expression (a heavy top's pivot inertia with
# r_cm a parameter: diagonal for r_cm on a principal axis, the usual top). Their right-hand
# side multiplies by 3 moments instead of 9 entries, twice: on heavy_top's and
# top_on_shaker's RK4 step 12-15 % of the work, what a hand-written step for the numbers
# at hand saves (rbfmu bench, fmu/c/bench_reference.c). The Gauss steps, ~100 times
# dearer, spend their time in Newton's linear algebra.
PRINCIPAL_VARIANTS = ("rk4", "rk8")


def principal_steps(a: Assembly, xdot: ca.SX, derived: ca.Function, project: ca.Function) -> dict[str, ca.Function]:
    """model_step_<m>_principal (and <m>_fixed_principal) for the PRINCIPAL_VARIANTS compiled
    in: the steps with d's off-diagonal inertia entries (`Assembly.off_diagonal`) set to 0,
    which CasADi's simplification then drops. Generated only when the scene's own parameters
    make those entries exactly 0; the FMU then tests them after every parameter change to
    choose the steps (RigidBodyModel.principal_test; rbfmu_core.c, rb_principal). With a
    clock, xdot has its sine and cosine as symbols (Assembly.clock): closed for the steps
    under error control, kept for the fixed ones' clock (`clock_of`)."""
    methods = [m for m in a.scene.methods if m in PRINCIPAL_VARIANTS]
    if not a.off_diagonal or not methods:
        return {}
    p0 = np.array([v.start for v in a.variables if v.kind in (Kind.PARAM_FIXED, Kind.PARAM_TUNABLE)], dtype=float)
    assert p0.shape == (a.params.shape[0],), "parameters and their variables out of step"
    d0 = np.asarray(derived(ca.DM(p0))).ravel()
    if np.any(d0[a.off_diagonal] != 0.0):
        return {}
    zero = set(a.off_diagonal)
    x, u, p, d = a.states, a.inputs, a.params, a.derived_params
    d_principal = ca.vertcat(*[ca.SX(0) if k in zero else d[k] for k in range(d.shape[0])])
    xdot = ca.substitute(xdot, d, d_principal)
    closed = xdot if a.clock is None else close_clock(a, xdot)
    rhs = ca.Function("model_rhs_principal", [x, u, p, d], [closed], ["x", "u", "p", "d"], ["xdot"])
    return method_steps(a, methods, rhs, project, principal=True, clock=clock_of(a, xdot))


def output_rates(a: Assembly, xdot: ca.SX, y: ca.SX) -> ca.Function:
    """First and second time derivatives of every output z = (x, y) (the states are
    outputs too) for FMI's output derivatives: ż = ∂z/∂x ẋ + ∂z/∂u u̇ and z̈ the same
    once more, with the inputs' derivatives u̇, ü given (FMI 2.0 input derivatives; zero
    for held inputs). Forward-mode AD of the outputs' own expressions (CasADi jtimes)."""
    x, u, p, d = a.states, a.inputs, a.params, a.derived_params
    u1, u2 = ca.SX.sym("u1", u.shape[0]), ca.SX.sym("u2", u.shape[0])
    z = ca.vertcat(x, y)
    z1 = ca.jtimes(z, ca.vertcat(x, u), ca.vertcat(xdot, u1))
    z2 = ca.jtimes(z1, ca.vertcat(x, u, u1), ca.vertcat(xdot, u1, u2))
    return ca.Function(
        "model_output_rates", [x, u, p, d, u1, u2], [z1, z2], ["x", "u", "p", "d", "u1", "u2"], ["z1", "z2"]
    )


def error_norm(a: Assembly) -> ErrorNorm:
    """(x0, e1, e2, ...) -> per state vector b (q, ω, and x, v of a moving reference point)
    (|e1_b|², |e2_b|², ..., nominal_b² + |x0_b|²), x0 the state at the start of the step:
    the squared relative errors of the vector over one scale, with
    the nominal as an absolute floor added to the scale (the usual atol + rtol·|x| of
    Hairer-Nørsett-Wanner I §II.4, in squares). The error control keeps their sum below
    (tolerance·h)² (docs/theory.md §5.5). Euclidean norms per vector, so the measure does
    not depend on the orientation of the frames; the nominals come from modelsrc.nominals.
    Squares and sums, because square roots, maxima (selects) and divisions of the error
    norm are what an RK4 step of a few hundred flops pays for its estimate: the controller
    works with ρ² (rbfmu_control.c), and DOP853's estimate combines two errors over one
    denominator. q is unit (projected after every step) and its nominal 1: its scale is 1."""
    nominal = state_nominals(a.scene)
    blocks = [(0, 4, nominal["q"]), (4, 7, nominal["w_body"])]
    for part, i in zip(a.state_parts, state_offsets(a)):  # x, v of a moving reference point, Ω, θ ...
        blocks.append((i, i + part.symbol.shape[0], nominal[part.name]))

    def norm(x0, *errors) -> list:
        out = []
        for i, j, n in blocks:
            scale2 = 1.0 if i == 0 and n == 1.0 else float(n) ** 2 + ca.sumsqr(x0[i:j])
            out.append((*(ca.sumsqr(e[i:j]) for e in errors), scale2))
        return out

    return norm


def step_builders(
    a: Assembly, rhs: ca.Function, project: ca.Function, clock: Clock | None = None
) -> dict[str, Callable[..., ca.Function]]:
    """Method name -> builder(function name) -> the step Function
    (x, U, p, h, d, k1, e) -> (x_next, err, est, k_next, dx) (modelsrc.integrators); the
    builders of FIXED_VARIANTS also take estimate=False (the step without its estimate,
    for rk4 and rk8 with the clock's angles by angle addition)."""
    nu, np_, nx, nd = a.inputs.shape[0], a.params.shape[0], a.states.shape[0], a.derived_params.shape[0]
    norm = error_norm(a)
    Id_expr = ca.diag(a.inertia)
    I_diag = ca.Function("I_diag", [a.params, a.derived_params], [Id_expr])
    # the reference point's acceleration depends on the orientation and the inputs only
    # (forces turning with the body, a_pivot): the splittings' translational kick (§7.4);
    # not in a central field, which depends on x_cm too and excludes the splittings (§9.7), nor
    # with propellers whose rate is a state (command mode, §8.8: the thrust depends on Ω)
    kick_args = {s.name() for s in ca.symvar(ca.vertcat(a.quaternion, a.inputs, a.params, a.derived_params))}
    free = a.position is not None and all(s.name() in kick_args for s in ca.symvar(a.acceleration))
    accel = (
        ca.Function("accel", [a.quaternion, a.inputs, a.params, a.derived_params], [a.acceleration]) if free else None
    )
    c_index = a.friction_index

    def friction(p_: ca.SX) -> ca.SX | None:
        return p_[c_index] if c_index is not None else None

    def split(name: str, exact: bool) -> ca.Function:
        # the axes ordered by their moments, ranked once per parameter change (model.finish_inertia)
        # made here, for the splittings only: in an orbit the torque depends on the orbit
        # angle too, and the orbit excludes them (modelsrc.features.orbit)
        torque = ca.Function("torque", [a.quaternion, a.inputs, a.params, a.derived_params], [a.conservative_torque])
        sym = a.split_axes if a.split_axes is not None else ca.SX.zeros(12)
        axes = ca.Function("axis_order", [a.derived_params], [sym[0:3], sym[3:6], sym[6:9], sym[9], sym[10], sym[11]])
        return splitting_step(project, nx, nu, np_, nd, torque, I_diag, axes, friction, name, exact=exact, accel=accel)

    return {
        "rk4": lambda n, estimate=True: rk4_step(rhs, project, norm, nd, n, estimate, clock),
        "rk8": lambda n, estimate=True: rk8_step(rhs, project, norm, nd, n, estimate, clock),
        "implicit_midpoint": lambda n: gauss_step(rhs, project, norm, nd, "implicit_midpoint", n),
        "gauss4": lambda n, estimate=True: gauss_step(
            rhs, project, norm, nd, "gauss4", n, estimate=estimate, newton_name="model_step_gauss4"
        ),
        "gauss6": lambda n, estimate=True: gauss_step(
            rhs, project, norm, nd, "gauss6", n, estimate=estimate, newton_name="model_step_gauss6"
        ),
        "splitting": lambda n: split(n, exact=False),
        "exact_free": lambda n: split(n, exact=True),
    }
