"""The generated functions of a scene's model: right-hand side, outputs, checks, Jacobian and integrator steps.

`model.build_model` assembles the equations feature by feature (an `Assembly`); this
module turns them into the CasADi Functions whose C is generated (fmu/codegen.py) and
adds the derived outputs the scene asks for. Every function of the state takes the
derived parameters d (`model_derived(p)`, evaluated by the FMU once per parameter
change) after p.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import casadi as ca
import numpy as np

from . import rigid_body as rb
from .assembly import Assembly
from .free_motion import motion_outputs
from .integrators import FIXED_VARIANTS, ErrorNorm, gauss_step, rk4_step, rk8_step, splitting_step
from .nominals import state_nominals
from .orbit import orbit_outputs
from .quaternion import euler_zxz, normalized
from .rotors import rotor_energy, rotor_momentum, rotor_outputs
from .variables import Kind, Variable, vector_names


def derived_outputs(a: Assembly, w_dot: ca.SX) -> ca.SX:
    """The derived outputs the scene requests, in the order of scene.OUTPUTS; their
    variables are appended to the assembly. Returns y."""
    # with rotors: E and L of the whole gyrostat (docs/theory.md §8.2); both terms 0 without
    Ek = rb.kinetic_energy(a.I, a.w) + rotor_energy(a)
    Lb = rb.angular_momentum_body(a.I, a.w) + rotor_momentum(a)
    w_world = a.R @ a.w
    derived = {
        "w_world": (w_world, "rad/s", "angular velocity, world axis {}"),
        "euler_zxz": (euler_zxz(a.R), "rad", "z-x-z Euler angle {} (phi, theta, psi)"),
        "E_kin": (Ek, "J", "rotational kinetic energy"),
        "E_total": (Ek + a.V if a.V is not None else Ek, "J", "kinetic + potential energy (pivot reference)"),
        "L_world": (a.R @ Lb, "N.m.s", "angular momentum, world axis {}"),
        "L_body": (Lb, "N.m.s", "angular momentum, body axis {}"),
    }
    derived.update(motion_outputs(a, w_dot))  # a moving reference point (docs/theory.md §7)
    if a.r_sensor is not None:
        # a body point from the reference point B: r, v = v_B + ω × r,
        # a = a_B + ω̇ × r + ω × (ω × r) (docs/theory.md §1.4, §7.2); B fixed: v_B = a_B = 0
        r_world = a.R @ a.r_sensor
        moving = a.pos is not None
        sensor = ca.vertcat(
            r_world if a.pos is None else a.pos + r_world,
            rb.point_velocity(w_world, r_world, a.vel if moving else None),
            rb.point_acceleration(w_world, a.R @ w_dot, r_world, a.accel if moving else None),
        )
        derived["sensor"] = (sensor, None, None)  # type: ignore[assignment]
    if "tau_bearing" in a.scene.outputs:
        derived["tau_bearing"] = (
            a.R @ rb.inverse_dynamics_torque(a.I, a.w, w_dot),
            "N.m",
            "torque the bearings supply to hold the rate, world axis {}",
        )
    parts = []
    # every rotor's and the orbit's (docs/theory.md §9.4), before the requested ones
    for name, expr, unit, desc in rotor_outputs(a, w_dot) + orbit_outputs(a):
        parts.append(expr)
        a.variables.append(Variable(name, Kind.OUTPUT, None, unit, desc))
    for name in a.scene.outputs:
        if name not in derived:
            continue  # the states q, w_body are outputs already
        expr, unit, desc = derived[name]
        parts.append(expr)
        if name == "sensor":
            for base, unit_, what in (
                ("sensor_r", "m", "position"),
                ("sensor_v", "m/s", "velocity"),
                ("sensor_a", "m/s2", "acceleration"),
            ):
                a.add(
                    vector_names(base, 3),
                    Kind.OUTPUT,
                    [None] * 3,
                    unit_,
                    [f"{what} of the sensor point, world axis {i}" for i in (1, 2, 3)],
                )
        elif expr.shape[0] == 1:
            a.variables.append(Variable(name, Kind.OUTPUT, None, unit, desc))
        else:
            n = expr.shape[0]
            a.add(vector_names(name, n), Kind.OUTPUT, [None] * n, unit, [desc.format(i) for i in range(1, n + 1)])
    return ca.vertcat(*parts) if parts else ca.SX.zeros(0, 1)


def model_functions(a: Assembly, xdot: ca.SX, y: ca.SX, xdot_principal: ca.SX | None = None) -> dict[str, ca.Function]:
    """rhs, rate, project, outputs, Jacobian, checks, derived parameters, output
    derivatives and one step function per method; xdot_principal: the right-hand side on
    principal axes for the steps of a full tensor diagonal as set (`principal_steps`)."""
    x, u, p, d = a.x, a.u, a.p, a.d
    rhs = ca.Function("model_rhs", [x, u, p, d], [xdot], ["x", "u", "p", "d"], ["xdot"])
    # Time scales that size the automatic sub-steps (docs/theory.md §5.4): ||∂f/∂x||∞ >=
    # ρ(∂f/∂x) (1/s: spin, friction c/I, gravity) for stability, and |ω| (rad/s) for accuracy.
    # Over the rotation (q, ω, and the rotor rates Ω, which couple with ω, §8) only: positions
    # and velocities of the reference point never act back on it, so ∂f/∂x is block
    # triangular and its other eigenvalues are 0 (§7.4)
    # (and the orbit angle, last, on which the gravity-gradient torque depends, §9)
    nr = len(a.rotor_rates) + (a.orbit_angle is not None)
    rot = ca.vertcat(a.q, a.w, *a.rotor_rates, *([] if a.orbit_angle is None else [a.orbit_angle]))
    rot_dot = ca.vertcat(xdot[:7], xdot[x.shape[0] - nr :]) if nr else xdot[:7]
    jac_rot = ca.jacobian(rot_dot, rot)
    if a.orbit_angle is not None or a.scene.has("central_gravity"):  # slow turning in an orbit (§9.1, §9.7)
        jac_rot = orbit_scaled_jacobian(a, jac_rot)
    rate = ca.Function(
        "model_rate",
        [x, u, p, d],
        [ca.vertcat(ca.norm_inf(jac_rot), ca.norm_2(a.w))],
        ["x", "u", "p", "d"],
        ["rate"],
    )
    rest = [a.pos, a.vel] if a.pos is not None and a.vel is not None else []
    orbit = [] if a.orbit_angle is None else [a.orbit_angle]
    project = ca.Function(
        "model_project", [x], [ca.vertcat(normalized(a.q), a.w, *rest, *a.rotor_rates, *orbit)], ["x"], ["x_projected"]
    )
    outputs = ca.Function("model_outputs", [x, u, p, d], [y], ["x", "u", "p", "d"], ["y"])
    # Jacobian of (x, ẋ, y) w.r.t. (x, u) by CasADi's AD, dense column major: the FMU's
    # directional and adjoint derivatives (docs/fmi_layer.md)
    J = ca.densify(ca.jacobian(ca.vertcat(x, xdot, y), ca.vertcat(x, u)))
    jac = ca.Function("model_jac", [x, u, p, d], [J], ["x", "u", "p", "d"], ["J"])
    checks = ca.Function(
        "model_checks", [x, p, a.method], [ca.vertcat(*[c[1] for c in a.checks])], ["x", "p", "method"], ["g"]
    )
    derived = ca.Function("model_derived", [p], [a.d_expr], ["p"], ["d"])
    functions = {
        "model_outputs": outputs,
        "model_checks": checks,
        "model_project": project,
        "model_rhs": rhs,
        "model_rate": rate,
        "model_jac": jac,
        "model_derived": derived,
        "model_output_rates": output_rates(a, xdot, y),
    }
    functions.update(method_steps(a, a.scene.methods, rhs, project, principal=False))
    functions.update(principal_steps(a, xdot if xdot_principal is None else xdot_principal, derived, project))
    return functions


def orbit_scaled_jacobian(a: Assembly, jac: ca.SX) -> ca.SX:
    """D⁻¹ J D, D the nominals of (q, ω, Ω, θ) (modelsrc.nominals): the same eigenvalues, so
    its norm still bounds the spectral radius, but without the unit mix of ∂q̇/∂ω = ½ q (order 1
    whatever the spin): a body in orbit turns at n ~ 1e-3 rad/s, and the unscaled norm ~ 1 1/s
    would cap its steps at a few seconds where the dynamics' own time scale is 1/n (§9.1)."""
    nominal = state_nominals(a.scene)
    states = [n for n, r in a.scene.rotors.items() if not r.speed]  # speed-mode rates are inputs (§8.5)
    scale = [1.0] * 4 + [nominal["w_body"]] * 3 + [nominal[f"Omega_{n}"] for n in states]
    scale += [nominal["orbit_angle"]] if a.orbit_angle is not None else []
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
    a: Assembly, methods: Sequence[str], rhs: ca.Function, project: ca.Function, principal: bool
) -> dict[str, ca.Function]:
    """step_name -> step Function for each method, with and (FIXED_VARIANTS) without its
    error estimate, from the right-hand side rhs."""
    steps = step_builders(a, rhs, project)
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
    choose the steps (RigidBodyModel.principal_test; rbfmu_core.c, rb_principal)."""
    methods = [m for m in a.scene.methods if m in PRINCIPAL_VARIANTS]
    if not a.off_diagonal or not methods:
        return {}
    p0 = np.array([v.start for v in a.variables if v.kind in (Kind.PARAM_FIXED, Kind.PARAM_TUNABLE)], dtype=float)
    assert p0.shape == (a.p.shape[0],), "parameters and their variables out of step"
    d0 = np.asarray(derived(ca.DM(p0))).ravel()
    if np.any(d0[a.off_diagonal] != 0.0):
        return {}
    zero = set(a.off_diagonal)
    d_principal = ca.vertcat(*[ca.SX(0) if k in zero else a.d[k] for k in range(a.d.shape[0])])
    rhs = ca.Function(
        "model_rhs_principal", [a.x, a.u, a.p, a.d], [ca.substitute(xdot, a.d, d_principal)], ["x", "u", "p", "d"],
        ["xdot"],
    )  # fmt: skip
    return method_steps(a, methods, rhs, project, principal=True)


def output_rates(a: Assembly, xdot: ca.SX, y: ca.SX) -> ca.Function:
    """First and second time derivatives of every output z = (x, y) (the states are
    outputs too) for FMI's output derivatives: ż = ∂z/∂x ẋ + ∂z/∂u u̇ and z̈ the same
    once more, with the inputs' derivatives u̇, ü given (FMI 2.0 input derivatives; zero
    for held inputs). Forward-mode AD of the outputs' own expressions (CasADi jtimes)."""
    x, u, p, d = a.x, a.u, a.p, a.d
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
    if a.pos is not None:
        base = "cm" if a.scene.has("translation") else "pivot"
        blocks += [(7, 10, nominal[f"x_{base}"]), (10, 13, nominal[f"v_{base}"])]
    i0 = 13 if a.pos is not None else 7
    states = [n for n, r in a.scene.rotors.items() if not r.speed]  # speed-mode rates are inputs
    blocks += [(i0 + k, i0 + k + 1, nominal[f"Omega_{n}"]) for k, n in enumerate(states)]
    if a.orbit_angle is not None:  # the last state (§9.1)
        i1 = i0 + len(states)
        blocks.append((i1, i1 + 1, nominal["orbit_angle"]))

    def norm(x0, *errors) -> list:
        out = []
        for i, j, n in blocks:
            scale2 = 1.0 if i == 0 and n == 1.0 else float(n) ** 2 + ca.sumsqr(x0[i:j])
            out.append((*(ca.sumsqr(e[i:j]) for e in errors), scale2))
        return out

    return norm


def step_builders(a: Assembly, rhs: ca.Function, project: ca.Function) -> dict[str, Callable[..., ca.Function]]:
    """Method name -> builder(function name) -> the step Function
    (x, U, p, h, d, k1) -> (x_next, err, est, k_next, dx) (modelsrc.integrators); the
    builders of FIXED_VARIANTS also take estimate=False (the step without its estimate)."""
    nu, np_, nx, nd = a.u.shape[0], a.p.shape[0], a.x.shape[0], a.d.shape[0]
    norm = error_norm(a)
    Id_expr = ca.diag(a.I)
    I_diag = ca.Function("I_diag", [a.p, a.d], [Id_expr])
    # the reference point's acceleration depends on the orientation and the inputs only
    # (forces turning with the body, a_pivot): the splittings' translational kick (§7.4);
    # not in a central field, which depends on x_cm too and excludes the splittings (§9.7)
    free = a.pos is not None and not a.scene.has("central_gravity")
    accel = ca.Function("accel", [a.q, a.u, a.p, a.d], [a.accel]) if free else None
    c_index = a.c_index

    def friction(p_: ca.SX) -> ca.SX | None:
        return p_[c_index] if c_index is not None else None

    def split(name: str, exact: bool) -> ca.Function:
        # the axes ordered by their moments, ranked once per parameter change (model.finish_inertia)
        # made here, for the splittings only: in an orbit the torque depends on the orbit
        # angle too, and the orbit excludes them (modelsrc.scene_orbit)
        torque = ca.Function("torque", [a.q, a.u, a.p, a.d], [a.tau_conservative])
        sym = a.split_axes if a.split_axes is not None else ca.SX.zeros(12)
        axes = ca.Function("axis_order", [a.d], [sym[0:3], sym[3:6], sym[6:9], sym[9], sym[10], sym[11]])
        return splitting_step(project, nx, nu, np_, nd, torque, I_diag, axes, friction, name, exact=exact, accel=accel)

    return {
        "rk4": lambda n, estimate=True: rk4_step(rhs, project, norm, nd, n, estimate),
        "rk8": lambda n, estimate=True: rk8_step(rhs, project, norm, nd, n, estimate),
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
