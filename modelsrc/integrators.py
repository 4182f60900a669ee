"""Integrator steps generated from a right-hand side, with their embedded error estimates (docs/theory.md §5).

Every step is a CasADi Function whose C is generated; the FMU's C layer only calls it,
with fixed steps or with steps chosen from the estimate (docs/theory.md §5.4, §5.5):

    (x, U, p, h, d, k1, e) -> (x_next, err, est, k_next, dx)

x: state at the start; U: the inputs at the method's nodes t + c_k h (`stage_nodes`,
one column of nu values per node: held inputs repeat one column, interpolated inputs
(FMI 2.0 input derivatives, FMI 3.0 intermediate update) differ, so a torque that varies
inside the step is integrated to the method's order); p: parameters; h: step (s);
d: the precomputed functions of p (`model_derived`: inertia about the rotation point and
its inverse, ...); k1 = f(x, u(t)); e: the step's constants, functions of p, d and h
that the C layer computes once per step size (`step_constants`: the sines and cosines of a
clock's advance to each stage, empty for a model without a clock). x_next ends with a projection onto |q| = 1
(Hairer-Lubich-Wanner, Geometric Numerical Integration, §IV.4: projection keeps the
order). err: the scaled Newton residual of an implicit step (else 0), which the C layer
tests; est: the square of the estimated relative error of the step (0 without an
estimate), the sum over the state vectors of |e_b|² / (nominal_b² + |x_b|²)
(`error_norm`; squared, so that neither the step nor the controller takes a square root);
k_next = f(x_next, u(t + h)), the next step's k1 (first same as last, FSAL), so that
the estimates cost no extra right-hand-side evaluation; dx: the increment x_next − x before
the projection (0 for the splittings), which the C layer adds with compensated summation to
the states other than q (Kahan; Hairer-Lubich-Wanner §VIII.5): over 1e6 steps the rounding
of ω + Δω otherwise makes |L| and E random-walk by √N ε, which a fast spin turns into an
attitude error √N ε W T.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np
from numpy.polynomial import legendre as npleg
from numpy.polynomial import polynomial as nppoly

from .shared_subexpressions import merged_outputs

# The squared relative errors of each state vector block of a step, over one scale:
# (x0, e1, e2, ...) -> [(|e1_b|², |e2_b|², ..., scale_b²)] (model_functions.error_norm).
ErrorNorm = Callable[..., list]

# Methods whose fixed steps (tolerance 0) get a step function of their own without the
# error estimate (model_step_<method>_fixed): on an RK4 step of a few hundred flops the
# estimate (squared norms and a division per state vector) still costs a tenth of the
# step; the Gauss methods' estimate is a whole explicit companion step (gauss_step).
# The implicit midpoint rule's one extra evaluation is negligible next to its Newton solve.
FIXED_VARIANTS = ("rk4", "rk8", "gauss4", "gauss6")

# The Gauss-Legendre methods and their numbers of stages (gauss_step, stage_nodes).
GAUSS_STAGES = {"implicit_midpoint": 1, "gauss4": 2, "gauss6": 3}

# The methods whose step returns its increment dx = x_next − x before projection (the
# Runge-Kutta and Gauss steps); the C layer sums x + dx with compensation for these
# (rbfmu_step.c, rb_call_step). The splittings compose flows and return dx = 0.
INCREMENT_METHODS = ("rk4", "rk8", *GAUSS_STAGES)


@dataclass(frozen=True)
class Clock:
    """An angle state θ = x[index] (rad) that advances at a rate n(p, d) (rad/s) fixed over
    a step and enters the right-hand side only through sin θ and cos θ: the orbit angle
    (docs/theory.md §9.1). rhs(x, u, p, d, sc) is the right-hand side with sc = (sin θ,
    cos θ) given. A fixed step then takes the stage angles θ + c h n by angle addition from
    one sine and cosine of θ per step and those of the advances c h n, which depend on h
    and the parameters only and are computed once per step size (`step_constants`): an
    RK4 step evaluates sin and cos once instead of four times, a DOP853 step once instead
    of twelve times (each a libm sincos of ~140 instructions, docs/report/step_cost.md).
    Exact in exact arithmetic: the stage state's θ is θ + h Σ_j a_ij n = θ + c_i h n
    (Σ_j a_ij = c_i), since every stage rate of θ is n; in floating point the sine of a
    sum and the angle addition differ by a few units of the last place."""

    index: int
    rate: ca.Function
    rhs: ca.Function


def _symbols(rhs: ca.Function, n_nodes: int, nd: int, ne: int, kind=ca.SX):
    nx, nu = rhs.size1_in(0), rhs.size1_in(1)
    x = kind.sym("x", nx)
    U = kind.sym("U", nu * n_nodes)
    p = kind.sym("p", rhs.size1_in(2))
    h = kind.sym("h")
    d = kind.sym("d", nd)
    k1 = kind.sym("k1", nx)
    e = kind.sym("e", ne)
    return x, U, p, h, d, k1, e


def node_input(U, nu: int, k: int):
    """The inputs at node k of a step (a column of U)."""
    return U[k * nu : (k + 1) * nu]


def _node_index(nodes: Sequence[float], c: float) -> int:
    return int(np.argmin(np.abs(np.asarray(nodes) - c)))


def _function(name: str, args: tuple, x_next, err, est, k_next, dx) -> ca.Function:
    outs = [x_next, err, est, k_next, dx]
    if isinstance(args[0], ca.SX):
        # one node per distinct subexpression over all outputs (CasADi's cse): the stages
        # rebuild equal terms (h/2 at each stage, R(q) for each rotated vector, the rotor
        # momenta) that the SX graph otherwise evaluates again; 9 % of spacecraft_thruster's
        # RK4 step. The same numbers: only repeated evaluations go.
        outs = merged_outputs(outs)
    names_out = ["x_next", "err", "est", "k_next", "dx"]
    return ca.Function(name, list(args), outs, ["x", "U", "p", "h", "d", "k1", "e"], names_out)


def larger(a, b):
    """max(a, b) as a comparison and a select. CasADi's fmax is C99's fmax, a call into
    libm that the compiler may not inline (it must order NaNs): measured in the former
    error norms, such calls made an RK4 step 1.5 times slower. A NaN gives b here,
    harmless: a non-finite step is refused on its state (rbfmu_control.c)."""
    return ca.if_else(a > b, a, b)


def squared_estimate(pairs: list):
    """The squared relative error of a step: the sum over the blocks of num/den
    (`ErrorNorm` pairs; CasADi drops a division by the scale 1 of q), a Euclidean norm
    over the state vectors, no select."""
    return sum(num / den for num, den in pairs)


def _rk_stages(f, x, h, k1, A, c):
    """Stages k_1 (given) ... k_s of an explicit tableau (A strictly lower triangular);
    f(c_i, x_i): the right-hand side at stage i's state, at its node's inputs."""
    k = [k1]
    for i in range(1, len(c)):
        xi = x
        for j in range(i):
            if A[i, j] != 0.0:
                xi = xi + h * float(A[i, j]) * k[j]
        k.append(f(float(c[i]), xi))
    return k


def stage_rhs(rhs, U, p, d, nodes, nu) -> Callable:
    """f(c, x): rhs at state x and the inputs of the node c (a column of U)."""
    return lambda c, xi: rhs(xi, node_input(U, nu, _node_index(nodes, c)), p, d)


def clock_rhs(rhs_open, index: int, x, U, p, d, e, advances: Sequence[float], nodes, nu) -> Callable:
    """f(c, x_c) for a step with a clock (`Clock`): rhs_open at the stage state x_c with
    (sin, cos) of θ + c h n by angle addition, sin(θ + a) = sin θ cos a + cos θ sin a and
    cos(θ + a) = cos θ cos a − sin θ sin a, from sin θ and cos θ of the step's start
    (evaluated once) and e = (sin a, cos a) per advance a = c h n (`step_constants`)."""
    s0, c0 = ca.sin(x[index]), ca.cos(x[index])

    def f(c: float, xi):
        k = advances.index(c)
        sa, ca_ = e[2 * k], e[2 * k + 1]
        sc = ca.vertcat(s0 * ca_ + c0 * sa, c0 * ca_ - s0 * sa)
        return rhs_open(xi, node_input(U, nu, _node_index(nodes, c)), p, d, sc)

    return f


def _dop853(f, x, h, k1):
    """DOP853's 12 stages from x (k1 given) and its 8th-order increment Σ h b_i k_i
    (Hairer-Nørsett-Wanner I §II.10; tableau from scipy); f(c, x) as `_rk_stages` takes it."""
    from scipy.integrate._ivp import dop853_coefficients as dop

    s = dop.N_STAGES
    k = _rk_stages(f, x, h, k1, np.asarray(dop.A[:s, :s], float), [float(c) for c in dop.C[:s]])
    return k, h * sum(float(bi) * ki for bi, ki in zip(np.asarray(dop.B, float), k) if bi != 0.0)


def advances(method: str) -> tuple[float, ...]:
    """The fractions c of the step at which an explicit method evaluates the right-hand
    side beyond its start (its stages' c_i > 0 and 1 for k_next), distinct, in order: the
    advances of a clock whose sines and cosines a fixed step takes from `step_constants`."""
    if method == "rk4":
        return (0.5, 1.0)
    if method == "rk8":
        from scipy.integrate._ivp import dop853_coefficients as dop

        return tuple(sorted({float(c) for c in dop.C[1 : dop.N_STAGES]} | {1.0}))
    raise ValueError(f"no clock advances for method {method!r}: only rk4 and rk8 take them")


def constants_name(method: str) -> str:
    """The name of a method's generated step constants, the one rule for it:
    model_step_constants_<method> (`step_constants`)."""
    return f"model_step_constants_{method}"


def step_constants(clock: Clock, method: str, np_: int, nd: int) -> ca.Function:
    """The constants e of `method`'s fixed step with `clock`, (p, h, d) -> e =
    (sin(c h n), cos(c h n)) for each of its `advances` c, named `constants_name(method)`:
    the C layer computes them once per step size and passes them to the step."""
    p, h, d = ca.SX.sym("p", np_), ca.SX.sym("h"), ca.SX.sym("d", nd)
    n = clock.rate(p, d)
    e = ca.vertcat(*[v for c in advances(method) for v in (ca.sin(c * (h * n)), ca.cos(c * (h * n)))])
    return ca.Function(constants_name(method), [p, h, d], [e], ["p", "h", "d"], ["e"])


# The most CasADi instructions an explicit step may have with its right-hand side
# inlined at every stage. Generated x86-64 takes ~10.5 bytes per instruction, and a step runs
# straight through its code once, so beyond ~2,600 (27 KB) the step and the FMU's loop
# outgrow a 32 KB L1 instruction cache and every step refetches part of its code:
# sleeping_top's DOP853 step with its estimate (3,100 instructions, 32.6 KB) missed the
# cache ~107 times per step (cachegrind) and took 474 ns under error control against
# 377 ns in a bare loop, and heavy_top's rk8 step moved by up to 25 % with the layout of
# the binary. A larger step calls the right-hand side as a function instead (`called`):
# 12.8 KB, 400 ns. Smaller ones stay inlined, where the call's copies cost more than the
# cache misses they avoid (free_asymmetric rk8, 1,764 instructions: 185 ns inlined, 237 ns
# calling; the rk4 steps 20-60 % slower calling). docs/fmi_layer.md, Step cost, has the
# measurements. 2,750, not 2,600: at the boundary, top_on_shaker's fixed principal DOP853 step
# (2,703 instructions) took 232 ns inlined against 267 ns calling (callgrind 4,453 against
# 5,244 instructions), while quadrotor's (2,793) took 410 ns inlined against 260 ns calling
# (rbfmu bench pairs, 2026-11-27).
INLINE_LIMIT = 2750


# cached: the steps built from one rhs (rk8 with and without its estimate) share one
# function, which the generated C then holds once (CasADi's code generator keeps one copy
# per Function object; a new wrapper per step held a copy per step)
@functools.lru_cache(maxsize=16)
def called(rhs: ca.Function) -> ca.Function:
    """rhs as a function that the generated code calls instead of inlining its expressions
    (CasADi's never_inline): its C is emitted once and called at every stage."""
    args = rhs.sx_in()
    return ca.Function(
        f"{rhs.name()}_called", args, rhs.call(args), rhs.name_in(), rhs.name_out(), {"never_inline": True}
    )


def compact(build: Callable[[ca.Function], ca.Function], rhs: ca.Function) -> ca.Function:
    """build(rhs), with rhs inlined unless that step has more than INLINE_LIMIT instructions,
    else build(called(rhs))."""
    step = build(rhs)
    return step if step.n_instructions() <= INLINE_LIMIT else build(called(rhs))


def _explicit_step(build: Callable, rhs: ca.Function, clock: Clock | None, estimate: bool) -> ca.Function:
    """An explicit Runge-Kutta step, build(f, clock) with f the right-hand side to inline or
    call (`compact`): the clock's rhs and the clock where the step takes its angles by angle
    addition (its fixed variant, estimate False: a step under error control changes h at
    every step, so constants per step size would be recomputed per step; it evaluates sin
    and cos at each stage), else rhs and None."""
    if clock is None or estimate:
        return compact(lambda f: build(f, None), rhs)
    return compact(lambda f: build(f, clock), clock.rhs)


def _explicit_symbols(rhs: ca.Function, clock: Clock | None, method: str, nd: int) -> tuple:
    """(x, U, p, h, d, k1, e, f) of an explicit `method` step: its arguments (e: the clock's
    constants, empty without one) and f(c, x_c), the right-hand side at a stage's state and
    node: by the clock's angle addition (`clock_rhs`; rhs is then the clock's rhs(x, u, p, d,
    sc)), else at the node's inputs (`stage_rhs`)."""
    nodes = stage_nodes(method)
    ne = 2 * len(advances(method)) if clock is not None else 0
    x, U, p, h, d, k1, e = _symbols(rhs, len(nodes), nd, ne)
    nu = rhs.size1_in(1)
    if clock is None:
        f = stage_rhs(rhs, U, p, d, nodes, nu)
    else:
        f = clock_rhs(rhs, clock.index, x, U, p, d, e, advances(method), nodes, nu)
    return x, U, p, h, d, k1, e, f


def rk4_step(
    rhs: ca.Function,
    project: ca.Function,
    norm: ErrorNorm,
    nd: int,
    name: str,
    estimate: bool = True,
    clock: Clock | None = None,
) -> ca.Function:
    """Classic 4th-order Runge-Kutta (Hairer-Nørsett-Wanner I, §II.1) and its free
    order-3 companion y3 = x + h (k1/6 + k2/3 + k3/3 + k5/6), k5 = f(y4) the next step's
    k1: y4 − y3 = h (k4 − k5)/6 estimates the error of the order-3 solution, falling
    like h⁴ (estimate order 3; the step goes on with y4). estimate False: est = 0, the
    step of fixed stepping, which does not pay for an estimate it never reads
    (`FIXED_VARIANTS`), and with a clock its stage angles by angle addition (`Clock`;
    e from `step_constants`). rhs is inlined, or called when the step would be too large
    (`compact`)."""
    return _explicit_step(lambda f, ck: _rk4(f, project, norm, nd, name, estimate, ck), rhs, clock, estimate)


def _rk4(
    rhs: ca.Function,
    project: ca.Function,
    norm: ErrorNorm,
    nd: int,
    name: str,
    estimate: bool,
    clock: Clock | None = None,
) -> ca.Function:
    x, U, p, h, d, k1, e, f = _explicit_symbols(rhs, clock, "rk4", nd)
    A = np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]], dtype=float)
    k = _rk_stages(f, x, h, k1, A, [0.0, 0.5, 0.5, 1.0])
    # weights as products (h/6, h/3): a division by the constant 6 or 3 stays a division in
    # C (gcc may not replace it by an inexact product), one per state and stage
    h6, h3 = h * (1.0 / 6.0), h * (1.0 / 3.0)
    dx = h6 * (k[0] + k[3]) + h3 * (k[1] + k[2])
    x_next = project(x + dx)
    k_next = f(1.0, x_next)
    # |h/6 (k4 − k5)|² per vector as (h/6)² |k4 − k5|²: one product instead of one per state
    est = (h6 * h6) * squared_estimate(norm(x, k[3] - k_next)) if estimate else 0
    return _function(name, (x, U, p, h, d, k1, e), x_next, 0, est, k_next, dx)


def rk8_step(
    rhs: ca.Function,
    project: ca.Function,
    norm: ErrorNorm,
    nd: int,
    name: str,
    estimate: bool = True,
    clock: Clock | None = None,
) -> ca.Function:
    """8th-order explicit Runge-Kutta of Dormand-Prince (DOP853's 12 stages,
    Hairer-Nørsett-Wanner I §II.10; tableau from scipy) with its own error estimate:
    the 5th- and 3rd-order differences err5, err3 of the same 12 stages (k_next has
    weight 0 in both) combined per state vector as err5²/√(err5² + 0.01 err3²), which falls like h⁸
    (HNW I §II.10, DOP853's estimate; estimate order 7). estimate False: est = 0, the
    step of fixed stepping (`FIXED_VARIANTS`), with a clock's stage angles by angle
    addition (`Clock`). rhs is inlined, or called when the step would be too large (`compact`)."""
    return _explicit_step(lambda f, ck: _rk8(f, project, norm, nd, name, estimate, ck), rhs, clock, estimate)


def _rk8(
    rhs: ca.Function,
    project: ca.Function,
    norm: ErrorNorm,
    nd: int,
    name: str,
    estimate: bool,
    clock: Clock | None = None,
) -> ca.Function:
    from scipy.integrate._ivp import dop853_coefficients as dop

    x, U, p, h, d, k1, e, f = _explicit_symbols(rhs, clock, "rk8", nd)
    k, dx = _dop853(f, x, h, k1)
    x_next = project(x + dx)
    k_next = f(1.0, x_next)
    args = (x, U, p, h, d, k1, e)
    if not estimate:
        return _function(name, args, x_next, 0, 0, k_next, dx)
    K = [*k, k_next]
    e5 = h * sum(float(w) * ki for w, ki in zip(dop.E5, K) if w != 0.0)
    e3 = h * sum(float(w) * ki for w, ki in zip(dop.E3, K) if w != 0.0)
    # err5²/√(err5² + 0.01 err3²), squared, with err5² = n5/s, err3² = n3/s over the
    # block's one denominator s: n5² / (s (n5 + 0.01 n3)), no square root (0 where both vanish)
    parts = []
    for n5, n3, scale2 in norm(x, e5, e3):
        den = scale2 * (n5 + 0.01 * n3)
        parts.append(ca.if_else(den > 0, n5 * n5 / larger(den, 1e-300), 0))
    return _function(name, args, x_next, 0, sum(parts), k_next, dx)


def gauss_tableau(s: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Legendre collocation tableau (A, b, c) with s stages, order 2s.

    Nodes c are the roots of the shifted Legendre polynomial; a_ij = ∫₀^{c_i} ℓ_j,
    b_j = ∫₀¹ ℓ_j with ℓ_j the Lagrange polynomials on c (Hairer-Wanner II §IV.5).
    """
    nodes, _ = npleg.leggauss(s)
    c = (np.sort(nodes) + 1) / 2
    A = np.zeros((s, s))
    b = np.zeros(s)
    for j in range(s):
        others = np.delete(c, j)
        lj = nppoly.polyfromroots(others) / np.prod(c[j] - others)
        Lj = nppoly.polyint(lj)
        b[j] = nppoly.polyval(1.0, Lj)
        A[:, j] = nppoly.polyval(c, Lj)
    return A, b, c


def gauss_step(
    rhs: ca.Function,
    project: ca.Function,
    norm: ErrorNorm,
    nd: int,
    method: str,
    name: str,
    newton_tol: float = 1e-14,
    max_iter: int = 20,
    estimate: bool = True,
    newton_name: str | None = None,
) -> ca.Function:
    """Implicit Gauss-Legendre step of `method` with s = GAUSS_STAGES[method] stages
    (s = 1: implicit midpoint).

    Order 2s, A-stable, symplectic; preserves every quadratic invariant exactly (|q|,
    and |L|² and 2T of the free body) up to the Newton tolerance (Hairer-Lubich-Wanner
    §IV.2). Stage increments Z_i = h Σ_j a_ij f(x + Z_j, u(c_j)) are solved with
    CasADi's code-generable `fast_newton` rootfinder (exact Jacobian, ||residual||∞ ≤
    newton_tol or max_iter iterations), from the predictor Z_i = c_i h k1;
    x_next = x + Σ_j d_j Z_j with dᵀ = bᵀA⁻¹, which saves s right-hand-side evaluations.

    Estimate (docs/theory.md §5.5). s = 1: the stage F = f((x + x_next)/2) cannot serve:
    its point is off the solution by h²/8 ẍ, and Simpson's rule on it reproduces the
    midpoint step to O(h⁴) (for ẋ = λx exactly: the estimate loses an order, and the
    controller let the error run 40-100 times over the tolerance). Simpson's rule is taken
    instead with one more evaluation at the cubic Hermite midpoint of the step, m = (x +
    x_next)/2 − (h/8)(k_next − k1), accurate to O(h³) with the step's own error: ŷ = x +
    (h/6)(k1 + 4 f(m) + k_next) errs by O(h⁴), so ŷ − x_next is the midpoint rule's local
    error, −(h³/12) λ³ x for ẋ = λx (Hairer-Nørsett-Wanner I §II.4): an estimate of order 2.
    s >= 2: no estimate from the stages serves: a quadrature of k1, the stage derivatives
    and k_next that leaves a stage out vanishes whenever the motion is linear in the state
    (a steady spin: the collocation defect is then ∝ Π(t − c_i) and the quadrature cancels
    it; measured 1e-17 against a true error of 4e-5 on skewed_bar, gauss4, h = 0.1 s), and
    the defect k1 − u'(0) is of order s only, 1e2-1e6 times the true error of the order-2s
    step. The estimate is the difference to a companion of higher order from the same
    start instead, DOP853's 8th-order increment (11 more evaluations of f, against a
    Newton solve of 100-700): its error falls like h⁹, the Gauss step's like h^(2s+1)
    (h⁵, h⁷), so the difference is the Gauss step's own local error to leading order, an
    estimate of order 2s. The companion is explicit: where h·||∂f/∂x|| passes its
    stability bound (~4) its error grows and the estimate rejects the step, so under error
    control a stiff motion is stepped at the explicit bound (fixed steps, tolerance 0,
    keep the A-stable step; they call the variant without the companion, `FIXED_VARIANTS`).
    estimate False: est = 0. newton_name: the name of the stage equations and their Newton
    solver (`gauss_newton`; default: name), shared by the variants with and without the
    estimate when they pass the same one.
    """
    s = GAUSS_STAGES[method]
    A, b, c = gauss_tableau(s)
    dw = np.linalg.solve(A.T, b)
    nodes = stage_nodes(method)
    nx, nu = rhs.size1_in(0), rhs.size1_in(1)
    x, U, p, h, d, k1, e = _symbols(rhs, len(nodes), nd, 0, ca.MX)
    G, solver = gauss_newton(rhs, method, nd, newton_name or name, newton_tol, max_iter)
    guess = ca.vertcat(*[float(c[i]) * h * k1 for i in range(s)])  # explicit Euler predictor
    Zvec = solver(guess, x, U, p, h, d)
    Zsol = ca.vertsplit(Zvec, nx)
    dx = sum(float(dw[j]) * Zsol[j] for j in range(s))
    x_next = project(x + dx)
    k_next = rhs(x_next, node_input(U, nu, len(nodes) - 1), p, d)
    est = 0
    if s == 1 and estimate:
        mid = rhs(x + 0.5 * dx - (h / 8) * (k_next - k1), node_input(U, nu, _node_index(nodes, 0.5)), p, d)
        est = squared_estimate(norm(x, (h / 6) * (k1 + 4 * mid + k_next) - dx))
    elif estimate:
        # the Gauss step's local error as its difference to DOP853's (h⁹ against h^(2s+1))
        _, dx8 = _dop853(stage_rhs(rhs, U, p, d, nodes, nu), x, h, k1)
        est = squared_estimate(norm(x, dx - dx8))
    # err: scaled residual left by Newton; the C layer rejects the step above NEWTON_ACCEPT
    err = ca.norm_inf(G(Zvec, x, U, p, h, d)) / ca.fmax(1, ca.norm_inf(Zvec))
    return _function(name, (x, U, p, h, d, k1, e), x_next, err, est, k_next, dx)


# cached: the Gauss steps with and without their estimate (FIXED_VARIANTS) solve the same
# stage equations; one residual, Jacobian and Newton solver Function serves both, so the
# generated C holds them once (CasADi emits one copy per Function object): 14 % less C to
# compile per FMU (measured on free_asymmetric, 480 kB of model_funcs.c)
@functools.lru_cache(maxsize=16)
def gauss_newton(
    rhs: ca.Function, method: str, nd: int, name: str, newton_tol: float, max_iter: int
) -> tuple[ca.Function, ca.Function]:
    """The stage equations of the Gauss-Legendre `method` on rhs, G(Z, x, U, p, h, d) =
    Z_i − h Σ_j a_ij f(x + Z_j, u(c_j)) (Z: the s stage increments stacked), and CasADi's
    code-generable `fast_newton` rootfinder on them (exact Jacobian, ||G||∞ ≤ newton_tol
    or max_iter iterations): (Z0, x, U, p, h, d) -> Z."""
    s = GAUSS_STAGES[method]
    A, _, c = gauss_tableau(s)
    nodes = stage_nodes(method)
    nx, nu = rhs.size1_in(0), rhs.size1_in(1)
    x, U, p, h, d, _, _ = _symbols(rhs, len(nodes), nd, 0, ca.MX)
    Z = ca.MX.sym("Z", nx * s)
    Zs = ca.vertsplit(Z, nx)
    F = [rhs(x + Zj, node_input(U, nu, _node_index(nodes, float(c[j]))), p, d) for j, Zj in enumerate(Zs)]
    res = ca.vertcat(*[Zs[i] - h * sum(float(A[i, j]) * F[j] for j in range(s)) for i in range(s)])
    G = ca.Function(f"{name}_residual", [Z, x, U, p, h, d], [res])
    solver = ca.rootfinder(
        f"{name}_newton", "fast_newton", G, {"abstol": newton_tol, "abstolStep": 0.0, "max_iter": max_iter}
    )
    return G, solver


def stage_nodes(method: str, estimate: bool = True) -> tuple[float, ...]:
    """The times c_k (fractions of the step) at which a method's step reads its inputs,
    sorted, always with 0 and 1: the columns of U (the C layer fills them; one per node).
    estimate False: those its step without the estimate reads (`FIXED_VARIANTS`), a
    subset; the C layer asks an importer only at these under fixed stepping."""
    if method == "rk4":
        return (0.0, 0.5, 1.0)
    if method == "rk8":
        from scipy.integrate._ivp import dop853_coefficients as dop

        return tuple(sorted({float(c) for c in dop.C[: dop.N_STAGES]} | {0.0, 1.0}))
    # the Gauss methods: the collocation nodes, and from 2 stages on those of the DOP853
    # companion step of their estimate (gauss_step)
    if method in GAUSS_STAGES:
        own = {0.0, *(float(c) for c in gauss_tableau(GAUSS_STAGES[method])[2]), 1.0}
        companion = estimate and GAUSS_STAGES[method] >= 2
        return tuple(sorted(own | set(stage_nodes("rk8")) if companion else own))
    return (0.0, 1.0)  # the splittings: a kick at each end


def splitting_step(
    project: ca.Function,
    nx: int,
    nu: int,
    np_: int,
    nd: int,
    torque: ca.Function,
    I_diag: ca.Function,
    axis_order: ca.Function,
    friction_c: Callable[[ca.SX], ca.SX | None],
    name: str,
    exact: bool = False,
    accel: ca.Function | None = None,
) -> ca.Function:
    """Explicit Lie-Poisson splitting (docs/theory.md §5.3), order 2:
    kick(h/2) ∘ damp(h/2) ∘ free flow(h) ∘ damp(h/2) ∘ kick(h/2)
    (Dullweber, Leimkuhler & McLachlan, J. Chem. Phys. 107, 1997). The kicks apply the
    torques that depend on the orientation and the inputs (gravity, torque inputs)
    exactly, L ← L + (h/2) τ(q, u), the first with the inputs at the start of the step,
    the last with those at its end (the trapezoidal rule: order 2 for inputs that vary).
    Friction is its exact exponential decay. The free flow is the composition of axis
    rotations in the order of the moments (`rigid_body.free_flow_split`, `axis_order`),
    or with exact=True the exact torque-free flow (`exact_free_flow`, Celledoni et al.
    2008): then a scene without torques is integrated exactly at any step. Needs
    principal body axes. No error estimate (est = 0, k_next = 0): these methods take
    fixed steps (modelsrc.methods.error_controlled).

    With a moving reference point (states x[7:10] position, x[10:13] velocity, world) the
    kicks also give the velocity (h/2) a(q, u) and the free flow drifts the position by
    h v, the exact flows of v̇ = a and ẋ = v (docs/theory.md §7.4): a constant a (uniform
    gravity, world forces, a held pivot acceleration) gives the exact parabola.

    torque(q, u, p, d) -> τ (body frame, without friction); I_diag(p, d) -> the 3
    principal moments about the rotation point; axis_order(d) -> (e_a, e_b, e_c, I_a,
    I_b, I_c); friction_c(p) -> c or None; accel(q, u, p, d) -> a (m/s², world) or None.
    """
    from . import rigid_body as rb
    from .exact_free_flow import exact_free_flow

    x = ca.SX.sym("x", nx)
    U = ca.SX.sym("U", nu * 2)
    p = ca.SX.sym("p", np_)
    h = ca.SX.sym("h")
    d = ca.SX.sym("d", nd)
    k1 = ca.SX.sym("k1", nx)
    e = ca.SX.sym("e", 0)
    u0, u1 = node_input(U, nu, 0), node_input(U, nu, 1)
    Id = ca.vertsplit(I_diag(p, d))
    c = friction_c(p)
    q, w = x[0:4], x[4:7]
    L = ca.vertcat(*[Id[i] * w[i] for i in range(3)])
    L = L + 0.5 * h * torque(q, u0, p, d)
    if accel is not None:
        pos, vel = x[7:10], x[10:13] + 0.5 * h * accel(q, u0, p, d)  # kick
    if c is not None:
        L = rb.friction_flow(L, Id, c, 0.5 * h)
    if exact:
        q, w_mid = exact_free_flow(q, ca.vertcat(*[L[i] / Id[i] for i in range(3)]), Id, h)
        L = ca.vertcat(*[Id[i] * w_mid[i] for i in range(3)])
    else:
        q, L = rb.free_flow_split(q, L, h, axis_order(d))
    if c is not None:
        L = rb.friction_flow(L, Id, c, 0.5 * h)
    L = L + 0.5 * h * torque(q, u1, p, d)
    w_next = ca.vertcat(*[L[i] / Id[i] for i in range(3)])
    x_next = ca.vertcat(q, w_next)
    if accel is not None:
        pos = pos + h * vel  # drift
        x_next = ca.vertcat(x_next, pos, vel + 0.5 * h * accel(q, u1, p, d))  # kick at the new orientation
    return _function(name, (x, U, p, h, d, k1, e), project(x_next), 0, 0, ca.SX.zeros(nx), ca.SX.zeros(nx))
