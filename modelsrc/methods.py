"""The integrator table: every method's name, FMI enumeration value, order, what it preserves and needs.

This is the one source of these facts. The step builders (``integrators``), the scene
reader (which methods a scene may compile in), the generated C (``fmu/build/model_data.py``),
the modelDescription's ``Method`` enumeration and the docs tables
(``fmu/docs_tables.py`` -> docs/methods.md, docs/fmi_layer.md, docs/importing.md) all
read it from here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Method:
    """One integrator of the FMU.

    value: the FMI enumeration value, the same in every FMU (FMI 2.0 has no enumeration
    names, so these integers are documented there). order: classical order of the
    method with torques acting (the exact flows are exact without them). preserves:
    what it keeps exactly (besides |q| = 1, which every method keeps by projection).
    needs_principal: the method works in principal axes about the point the body turns
    about (docs/theory.md §5.3). rate_limit: largest h·||∂f/∂x||∞ (stability of explicit
    methods; inf for A-stable and splitting methods); rotation_limit: largest h·|ω| in
    rad (accuracy at fast spin) (docs/theory.md §5.4). newton: implicit, solved by
    Newton's method, its residual checked after every step. cost: the work of one
    internal step in right-hand-side evaluations, what the tunable `work_limit` counts
    (WORK_LIMIT). estimate_order: the order q of the step's embedded error estimate (its
    size falls like h^(q+1)), which error-controlled stepping needs (docs/theory.md §5.5);
    None: no estimate, the method takes fixed steps whatever the tolerance. description:
    one line, as in the modelDescription's Method enumeration; use_for: when to choose it.
    """

    name: str
    value: int
    order: int
    kind: str
    preserves: str
    needs_principal: bool
    rate_limit: float
    rotation_limit: float
    newton: bool
    cost: float
    estimate_order: int | None
    description: str
    use_for: str

    @property
    def needs(self) -> str:
        """What the scene must satisfy for this method, in words ('' when nothing)."""
        return "principal axes about the rotation point" if self.needs_principal else ""


# Sub-step limits (docs/theory.md §5.4). Stability: RK4's region reaches 2.78 on the real
# and 2.83 on the imaginary axis, 2.616 at the least (the ray at 122°), the DOP853
# propagator's 5.96 at the least; ||J||∞ (the induced norm) bounds the spectral radius, so
# 1.0 and 1.5 keep a factor 2.6 and 4.0 for the rate to grow within a doStep. Rotation: the phase error per
# radian turned is C·(h|ω|/2)^p with C = 1/120 (RK4), 1/12 (midpoint), 1/720 (Gauss 4),
# 1/100800 (Gauss 6) (docs/robustness.md §1); at these limits 8e-7 (RK4: 0.2), 5e-5
# (implicit midpoint: 0.05; the order-2 splitting likewise), 7e-7 (Gauss 4: 0.3), 2e-9
# (Gauss 6: 0.5); rk8 (0.5) measured ~1e-12.
# Cost: the work of one internal step in right-hand-side evaluations, the unit of the
# tunable work_limit (docs/fmi_layer.md, Work limit). rk4 evaluates f 4 times; every other
# method is charged its time per step in units of an rk4 step, timed in C (gcc -O2, x86_64;
# the generated steps of free_asymmetric, heavy_top, torque_driven and the tests'
# extreme_free, the median, rounded) at the largest steps the layer takes, h|w| at 99 % of
# the rotation limit, where Newton iterates most: rk8 4.1x (12 stages and their
# combination), implicit midpoint 48x, Gauss 4 177x, Gauss 6 558x (Newton with the exact
# Jacobian and an LU solve of the 7s x 7s stage system), splitting 1.8x, exact_free 21x
# (elliptic functions). At the scenes' own h_max the Gauss methods iterate less and cost
# about a third of this. Fixed numbers, not a clock: whether a doStep is refused must not
# depend on the machine or its load.
_INF = math.inf
METHODS: dict[str, Method] = {
    m.name: m
    for m in (
        Method("rk4", 1, 4, "explicit Runge-Kutta", "-", False, 1.0, 0.2, False, 4, 3,
               "classic Runge-Kutta, order 4, explicit", "general use; the cheapest step"),
        Method("rk8", 2, 8, "explicit Runge-Kutta", "-", False, 1.5, 0.5, False, 16, 7,
               "Dormand-Prince 8th-order explicit Runge-Kutta (DOP853) with its 5th/3rd-order error estimates",
               "tight tolerances on smooth problems"),
        Method("implicit_midpoint", 3, 2, "implicit (Gauss-Legendre 1 stage)", "|L|, E (quadratic invariants)",
               False, _INF, 0.05, True, 200, 2,
               "implicit midpoint = Gauss-Legendre 1 stage, order 2, A-stable, keeps quadratic invariants",
               "long runs where invariants matter more than phase"),
        Method("gauss4", 4, 4, "implicit (Gauss-Legendre 2 stages)", "|L|, E (quadratic invariants)",
               False, _INF, 0.3, True, 700, 4,
               "Gauss-Legendre 2 stages, order 4, A-stable, keeps quadratic invariants",
               "long runs, stiff rotation"),
        Method("gauss6", 5, 6, "implicit (Gauss-Legendre 3 stages)", "|L|, E (quadratic invariants)",
               False, _INF, 0.5, True, 2200, 6,
               "Gauss-Legendre 3 stages, order 6, A-stable, keeps quadratic invariants",
               "long runs at tight tolerance"),
        Method("splitting", 6, 2, "explicit Lie-Poisson splitting", "|L| exactly; E bounded", True, _INF, 0.05,
               False, 8, None, "explicit Lie-Poisson splitting (axis rotations + torque kicks), order 2, exact |L|",
               "principal bodies over long runs; stiff friction (exact damping)"),
        Method("exact_free", 7, 2, "exact torque-free flow + kicks", "the whole torque-free motion (exact)", True,
               _INF, 0.25, False, 80, None,
               "exact torque-free flow (Jacobi elliptic functions, Celledoni et al. 2008), exact at any "
               "step without torques; kick - exact flow - kick, order 2, when torques act",
               "torque-free bodies at any step; fast spin; stiff friction"),
    )
}  # fmt: skip

# The methods whose flows are those of the rigid body alone: (q, ω) in an inertial frame,
# the torques held over a kick (the splittings, docs/theory.md §5.3). A feature that adds
# states, a turning frame or position-dependent torques refuses them (modelsrc.feature).
RIGID_FLOW_METHODS = ("splitting", "exact_free")

# A Gauss step is accepted when ||residual||∞ <= NEWTON_ACCEPT·max(1, ||Z||∞).
NEWTON_ACCEPT = 1e-10

# Error-controlled stepping (docs/theory.md §5.5). `tolerance` is a relative error per
# second of simulated time: an internal step of h seconds is accepted when its estimated
# relative error is at most tolerance·h/(1 s) (error per unit step, Shampine, "Numerical
# Solution of ODEs" §7.1: the error after T seconds is then about tolerance·T, whatever the
# importer's communication step and the body's spin), with absolute floors at each state
# vector's nominal value (modelsrc.nominals). DEFAULT_TOLERANCE is the start value of the
# tunable parameter `tolerance`; 0 selects fixed stepping (docs/theory.md §5.4).
DEFAULT_TOLERANCE = 1e-10
# No step is asked for an estimated relative error below ESTIMATE_FLOOR: the estimate of a
# step carries round-off of a few ε (ε = 2.2e-16) itself, so a smaller target cannot be
# told apart from zero and would only shrink the step (measured: the estimate of a step
# whose truncation error is far below it stays at 1-4 ε; docs/theory.md §5.5).
ESTIMATE_FLOOR = 1e-16

# Default of the tunable parameter work_limit: the most work one doStep may do, in
# right-hand-side evaluations (Method.cost per internal step, retries included): 1.25e7 rk4
# or 22,727 Gauss-6 steps, a few seconds of work at most (`rbfmu bench` times the longest
# doStep it admits per method: 0.9-3.4 s on the 2-core reference machine at a load of 6,
# docs/robustness.md §1). A longer doStep is deliberate: raise work_limit for it.
WORK_LIMIT = 5e7
# The largest work_limit accepted (a generated check refuses more): 1e15 evaluations, about
# three years of the cheapest step at 0.1 µs per evaluation, and below 2^53 = 9.0e15, so
# every count of internal steps the budget makes stays an exact integer in a double
# (fmu/c/rbfmu_budget.c; beyond 2^53, k - 1 == k: the doStep of issue 23.1 never returned).
WORK_LIMIT_MAX = 1e15


def error_controlled(method: str) -> bool:
    """True when the method has an embedded error estimate, so that `tolerance` > 0
    chooses its steps (docs/theory.md §5.5); the others always take fixed steps."""
    return METHODS[method].estimate_order is not None


def method_names() -> tuple[str, ...]:
    """All method names in enumeration order."""
    return tuple(METHODS)


def rotation_limit(method: str, exact_flow: bool) -> float:
    """θ_max (rad) of a method for a scene: the exact free flow needs none where it is
    exact (Scene.exact_flow: no torque, no force turning with the body)."""
    return math.inf if method == "exact_free" and exact_flow else METHODS[method].rotation_limit


def enumeration_value(value: object, allowed: dict[str, int]) -> float | None:
    """The enumeration value of a method given by name or by value among `allowed` (name ->
    value: every method, or those compiled into one FMU), as a float; None if it is neither."""
    by_name = allowed.get(str(value).strip())
    if by_name is not None:
        return float(by_name)
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) and v == int(v) and int(v) in allowed.values() else None


def method_by_value(value: int) -> Method:
    """The method with FMI enumeration value `value`; KeyError naming the allowed values."""
    for m in METHODS.values():
        if m.value == value:
            return m
    raise KeyError(
        f"no method has value {value}; values: " + ", ".join(f"{m.value}={m.name}" for m in METHODS.values())
    )
