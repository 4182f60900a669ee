"""The discrete step map of one communication step: Φ = ∂x(t+H)/∂x(t) and Γ = ∂x(t+H)/∂u, exact through the integrator.

The FMI Co-Simulation interface has no call for the derivatives of a doStep, so this API
computes them from the same generated CasADi step functions the FMU's C is made of
(`build_model(scene).functions["model_step_<method>"]`, `model_rhs`, `model_derived`,
`model_rate`): each internal step x_(k+1) = step(x_k, u, p, h, d, k1 = f(x_k, u)) is
differentiated by CasADi's AD (through the Newton solve of the Gauss methods by the
implicit function theorem) and the step Jacobians are chained,

    Φ = J_x(n) ⋯ J_x(1),   Γ = Σ_k J_x(n) ⋯ J_x(k+1) J_u(k),

with u held over the step (zero-order hold, as an MPC applies it). The internal steps are
the FMU's fixed stepping (docs/theory.md §5.4: `tolerance` = 0): n equal steps,
n = max(⌈H/h⌉, ⌈H ρ/ρ_max⌉, ⌈H |ω|/θ_max⌉) with h = h_max (the scene's fixed step when
h_max = 0) and ρ, |ω| from `model_rate` at the start, the FMU's own rule. Under error
control the FMU chooses its step sizes from the state (a piecewise-constant function of x,
not reported through FMI): the map is then that of fixed steps fine enough to be the
flow's to the tolerance, which is what the derivative of a controlled doStep is up to
O(tolerance) (docs/theory.md §10.3).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import casadi as ca
import numpy as np

from modelsrc.errors import ModelInputError
from modelsrc.integrators import constants_name
from modelsrc.methods import METHODS, NEWTON_ACCEPT, rotation_limit
from modelsrc.model import Kind, RigidBodyModel, build_model
from modelsrc.scene import Scene

from .attitude import chart
from .linear_model import LinearModel
from .operating_point import OperatingPoint

MAX_SUBSTEPS = 100_000  # the chained Jacobians cost ~20 µs per internal step: a few seconds at most


def parameters(model: RigidBodyModel, given: Mapping[str, float]) -> np.ndarray:
    """The parameter vector p of the generated functions: the start values, with `given`."""
    params = [v for v in model.variables if v.kind in (Kind.PARAM_FIXED, Kind.PARAM_TUNABLE)]
    return np.array([float(given.get(v.name, v.start)) for v in params])  # type: ignore[arg-type]


def method_name(model: RigidBodyModel, point: OperatingPoint, method: str | None) -> str:
    """The method: given, else the point's `method` parameter, else the scene's default;
    it must be compiled in."""
    if method is None and "method" in point.parameters:
        by_value = {m.value: m.name for m in METHODS.values()}
        method = by_value.get(int(point.parameters["method"]))
    method = method or model.default_method
    if method not in model.methods:
        raise ModelInputError(
            f"step map: method {method!r} is not compiled into this scene: {', '.join(model.methods)}"
        )
    return method


def substeps_for(model: RigidBodyModel, method: str, H: float, x: np.ndarray, u: np.ndarray, p: np.ndarray,
                 d: np.ndarray, h_max: float) -> int:  # fmt: skip
    """The FMU's number of fixed substeps of a doStep of H (docs/theory.md §5.4)."""
    rate, spin = (float(v) for v in np.asarray(model.functions["model_rate"](x, u, p, d)).ravel())
    n = math.ceil(H / h_max * (1 - 1e-12))
    lim = METHODS[method].rate_limit
    if math.isfinite(lim):
        n = max(n, math.ceil(H * rate / lim * (1 - 1e-12)))
    rot = rotation_limit(method, model.scene.exact_flow)
    if math.isfinite(rot):
        n = max(n, math.ceil(H * spin / rot * (1 - 1e-12)))
    return max(n, 1)


def step_jacobian(model: RigidBodyModel, method: str, p: np.ndarray, d: np.ndarray) -> ca.Function:
    """(x, u, h) -> (x_next, err, ∂x_next/∂(x, u)) of one fixed internal step, k1 = f(x, u)."""
    f = model.functions
    name = f"model_step_{method}_fixed" if f"model_step_{method}_fixed" in f else f"model_step_{method}"
    step = f[name]
    nx, nu = model.nx, model.nu
    x, u, h = ca.MX.sym("x", nx), ca.MX.sym("u", nu), ca.MX.sym("h")
    P, Dd = ca.DM(p), ca.DM(d)
    k1 = f["model_rhs"](x, u, P, Dd)
    nodes = step.size1_in(1) // nu if nu else 0
    U = ca.vertcat(*([u] * nodes)) if nu else ca.MX(step.size1_in(1), 1)
    # a clock's sines and cosines of its advances (modelsrc.integrators.step_constants), as the
    # FMU computes them per step size; an empty e for a step without them
    constants = f.get(constants_name(method))
    e = constants(P, h, Dd) if constants is not None and step.size1_in(6) else ca.MX(0, 1)
    x_next, err = step(x, U, P, h, Dd, k1, e)[:2]
    return ca.Function("step_jacobian", [x, u, h], [x_next, err, ca.jacobian(x_next, ca.vertcat(x, u))])


def step_map(
    scene: Scene,
    point: OperatingPoint,
    H: float,
    method: str | None = None,
    substeps: int | None = None,
    coordinates: str = "attitude",
    model: RigidBodyModel | None = None,
) -> LinearModel:
    """Φ, Γ of one communication step of H seconds from `point` (u held), as a discrete
    LinearModel (A = Φ, B = Γ, outputs = the states: C = 1, D = 0, dt = H).

    method: the integrator (default: the point's `method`, else the scene's); substeps:
    the internal steps (default: the FMU's fixed-stepping rule with the point's h_max, or
    the scene's fixed step); coordinates "attitude" (δθ at both ends: Φ_z = S(x_H) Φ T(x₀),
    the attitude at t + H taken from the nominal step's end; the orbit's clock left out) or
    "raw". model: build_model(scene), when the caller has it."""
    if not (math.isfinite(H) and H > 0):
        raise ModelInputError(f"step map: the step H must be a finite number > 0 (s), got {H}")
    if coordinates not in ("attitude", "raw"):
        raise ModelInputError(f"coordinates must be one of attitude, raw, got {coordinates!r}")
    model = model or build_model(scene)
    names = [v.name for v in model.variables if v.kind == Kind.STATE]
    inputs = [v.name for v in model.variables if v.kind == Kind.INPUT]
    if list(point.states) != names or list(point.inputs) != inputs:
        raise ModelInputError(
            f"step map: the point's states and inputs are not the scene {scene.name}'s: {names}, {inputs}"
        )
    m = method_name(model, point, method)
    p = parameters(model, point.parameters)
    d = np.asarray(model.functions["model_derived"](p)).ravel()
    x0, u = point.x, point.u
    h_max = float(point.parameters.get("h_max", scene.h_max)) or scene.fixed_step
    if substeps is None:
        n = substeps_for(model, m, H, x0, u, p, d, h_max)
    elif isinstance(substeps, (int, np.integer)) and 1 <= substeps <= MAX_SUBSTEPS:
        n = int(substeps)
    else:
        raise ModelInputError(f"step map: substeps must be a whole number from 1 to {MAX_SUBSTEPS:,}, got {substeps!r}")
    if n > MAX_SUBSTEPS:
        raise ModelInputError(f"step map: {n:,} internal steps of {m} needed for H = {H:g} s, at most {MAX_SUBSTEPS:,}")
    F = step_jacobian(model, m, p, d)
    nx = model.nx
    Phi, Gamma = np.eye(nx), np.zeros((nx, model.nu))
    x = x0.copy()
    for k in range(n):
        h = (k + 1) * H / n - k * H / n
        try:
            x_next, err, J = (np.asarray(v) for v in F(x, u, h))
        except RuntimeError as exc:  # CasADi's fast_newton fails the call where it does not converge
            if "rootfinder" not in str(exc):
                raise
            err = np.array(np.inf)
        if METHODS[m].newton and not err.item() <= NEWTON_ACCEPT:
            raise ModelInputError(
                f"step map: the {m} step's Newton iteration did not converge at internal step {k + 1} of {n} "
                f"(scaled residual {err.item():.3g}, accepted up to {NEWTON_ACCEPT:g}): its derivatives do not exist "
                "there; take more substeps"
            )
        Jx, Ju = J[:, :nx], J[:, nx:]
        Phi, Gamma = Jx @ Phi, Jx @ Gamma + Ju
        x = x_next.ravel()
    if not np.all(np.isfinite(x)):
        raise ModelInputError(f"step map: the state became non-finite over the step from {point.source}")
    if not (np.all(np.isfinite(Phi)) and np.all(np.isfinite(Gamma))):
        raise ModelInputError(
            f"step map: the derivative of the {m} step is not finite at this point although the step is (exact_free "
            "on a symmetric body: its elliptic functions' derivative at modulus 0 is 0/0); choose another --method"
        )
    common: dict[str, Any] = dict(inputs=tuple(inputs), point=point, dt=float(H), method=m, substeps=n)
    if coordinates == "raw":
        return LinearModel(A=Phi, B=Gamma, C=np.eye(nx), D=np.zeros((nx, model.nu)), states=tuple(names),
                           outputs=tuple(names), coordinates="raw", **common)  # fmt: skip
    start, end = chart(names, x0, "fixed"), chart(names, x, "fixed")
    A, B = end.S @ Phi @ start.T, end.S @ Gamma
    nz = len(start.states)
    return LinearModel(A=A, B=B, C=np.eye(nz), D=np.zeros((nz, model.nu)), states=start.states, outputs=start.states,
                       coordinates="attitude error", frame="step", **common)  # fmt: skip
