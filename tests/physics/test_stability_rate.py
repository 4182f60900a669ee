"""The fixed-step rule's rate bounds the spectral radius of ∂f/∂x, so its steps stay inside RK4's and DOP853's regions.

docs/theory.md §5.4: a doStep takes n ≥ H·ρ/ρ_max sub-steps, ρ = model_rate's first entry over
the rotation (q, ω, rotor rates, orbit angle). ρ was the largest entry max_ij |∂f_i/∂x_j|, which is
no bound of the spectral radius: sleeping_top with a point-like bob (I_principal = 1e-6 kg m² each)
whose centre of mass lies off the body axes (r_cm along (1, 1, 1)) and friction c = 1e-3 N m s has
the inverse inertia about the pivot nearly c/ε·r̂r̂ᵀ, whose entries are a third of its eigenvalue:
ρ = 334 1/s against a friction mode λ = −1000 1/s, so RK4 at h = 1/ρ had hλ = −2.99, outside its
interval (2.785), |R| = 1.36 per step (a run of that FMU at H = 0.02 s: 7 sub-steps, the spin grew
from 1 to 31 rad/s where it decays to 0.006). ρ is now the induced norm max_i Σ_j |∂f_i/∂x_j|
(model_functions.induced_inf_norm), ≥ the spectral radius. These tests evaluate the generated
functions of the CasADi model (no FMU): the bound at states along each shipped scene's start and
stiff settings, and h·|λ| of every decaying mode against the method's region at the rule's step.
The orbit's own modes (±√2 n, ±i n of the central field) were not in ρ at all: a spherical body at
rest in eccentric_orbit's field with μ = 100 μ_Earth had ρ = 0.00096 1/s against −√2 n = −0.0179
1/s (RK4: hλ = −18.7); ρ now takes √‖∂v̇/∂x‖∞ too (model_functions.translation_rate).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from modelsrc.model import Kind, build_model
from modelsrc.scene import list_scenes, load_scene

from ..harness.stability import left_half_radius, rule_step, stability_function

MU_EARTH = 3.986004418e14  # m³/s²
SKEW = 0.04 / math.sqrt(3.0)  # m: sleeping_top's r_cm length, along (1, 1, 1)
POINT_BOB = {
    **{f"r_cm[{k}]": SKEW for k in (1, 2, 3)},
    **{f"I_principal[{k}]": 1e-6 for k in (1, 2, 3)},
    "c_friction": 1e-3,
    "w_body[3]": 1.0,
}


def _point(model, given: dict[str, float]):
    """(x, u, p, d): the model's start state (q normalised, as initialisation does), inputs and
    parameters with `given` values, and its derived parameters."""
    values = {k: [float(given.get(v.name, v.start)) for v in model.variables if v.kind in kinds]
              for k, kinds in (("x", (Kind.STATE,)), ("u", (Kind.INPUT,)),
                               ("p", (Kind.PARAM_FIXED, Kind.PARAM_TUNABLE)))}  # fmt: skip
    x, u, p = (np.array(values[k]) for k in ("x", "u", "p"))
    x[:4] /= np.linalg.norm(x[:4])
    return x, u, p, np.asarray(model.functions["model_derived"](p=p)["d"]).ravel()


def _rate_and_modes(model, x, u, p, d):
    """(ρ, |ω|, the eigenvalues of the whole ∂f/∂x, those of its rotation block)."""
    nx, f = model.nx, model.functions
    rate, spin = (float(v) for v in np.asarray(f["model_rate"](x=x, u=u, p=p, d=d)["rate"]).ravel())
    J = np.asarray(f["model_jac"](x=x, u=u, p=p, d=d)["J"])[nx : 2 * nx, :nx]
    names = [v.name for v in model.variables if v.kind == Kind.STATE]
    translational = [k for k, n in enumerate(names) if n.startswith(("x_", "v_"))]
    rot = [k for k in range(nx) if k not in translational]
    return rate, spin, np.linalg.eigvals(J), np.linalg.eigvals(J[np.ix_(rot, rot)])


def _margin(model, x, u, p, d, method: str) -> float:
    """max over the decaying modes λ (Re λ ≤ 0) of h·|λ| / the method's left-half radius, h the rule's step."""
    rate, spin, modes, _ = _rate_and_modes(model, x, u, p, d)
    h = rule_step(method, rate, spin)
    decaying = [abs(lam) for lam in modes if lam.real <= 1e-12 * abs(lam)]
    if not decaying or not math.isfinite(h):
        return 0.0
    return h * max(decaying) / left_half_radius(method)


def test_a_body_at_rest_in_a_tighter_orbit_is_stable_at_the_rules_rk4_step():
    model = build_model(load_scene("eccentric_orbit"))
    at_rest = {**{f"I_principal[{k}]": 500.0 for k in (1, 2, 3)}, **{f"w_body[{k}]": 0.0 for k in (1, 2, 3)}}
    x, u, p, d = _point(model, {**at_rest, "mu": 100 * MU_EARTH})  # n = 10 × the perigee's
    rate, spin, modes, _ = _rate_and_modes(model, x, u, p, d)
    radial = modes[np.argmin(modes.real)]  # −√2 n: the stable one of the radial pair
    assert abs(abs(radial) - math.sqrt(2 * 100 * MU_EARTH / 6.3e6**3)) < 1e-9 * abs(radial)
    assert rate >= abs(radial) * (1 - 1e-12)  # the rotation block's norm alone was 0.00096 1/s, 19 times less
    assert abs(stability_function("rk4", rule_step("rk4", rate, spin) * radial)) < 1.0


def test_the_point_bob_with_friction_is_stable_at_the_rules_rk4_step():
    model = build_model(load_scene("sleeping_top"))
    x, u, p, d = _point(model, {**POINT_BOB, "g[3]": 0.0})
    rate, spin, modes, rot_modes = _rate_and_modes(model, x, u, p, d)
    friction = modes[np.argmax(np.abs(modes))]
    assert abs(friction + 1000.0) < 1e-6 * 1000.0  # −c/ε along r̂
    assert rate >= np.max(np.abs(rot_modes))  # the largest entry, 334, was not
    h = rule_step("rk4", rate, spin)
    assert abs(stability_function("rk4", h * friction)) < 1.0  # was 1.36 at h = 1/334 s


@pytest.mark.slow
@pytest.mark.parametrize("name", list_scenes())
def test_the_rate_bounds_the_rotation_blocks_spectral_radius_and_the_rules_steps_are_stable(name):
    model = build_model(load_scene(name))
    names = {v.name for v in model.variables}
    settings: list[dict[str, float]] = [{}]
    settings.append({v.name: 100.0 * float(v.start or 0.0) for v in model.variables if v.name.startswith("w_body[")})
    if "c_friction" in names:  # strong friction, and the point bob of the module docstring
        settings += [{"c_friction": 1e-2}, POINT_BOB, {**POINT_BOB, "g[3]": 0.0}]
    if "mu" in names:  # a spherical body at rest in the orbit: only the orbit's own modes (±√2 n, ±i n)
        at_rest = {**{f"I_principal[{k}]": 500.0 for k in (1, 2, 3)}, **{f"w_body[{k}]": 0.0 for k in (1, 2, 3)}}
        settings += [at_rest, {**at_rest, "mu": 100 * MU_EARTH}, {"mu": 100 * MU_EARTH}]
    for given in settings:
        x, u, p, d = _point(model, given)
        rate, _, _, rot_modes = _rate_and_modes(model, x, u, p, d)
        assert rate >= np.max(np.abs(rot_modes)) * (1 - 1e-12), (name, given)
        for method in ("rk4", "rk8"):
            assert _margin(model, x, u, p, d, method) <= 1.0, (name, given, method)
