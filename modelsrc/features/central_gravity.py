"""The central field as one feature (``central_gravity``): a free body's own orbit and its gravity-gradient torque.

The central body (gravitational parameter μ = G M, m³/s²) sits at the world origin; the
body's centre of mass is at x = x_cm (world). Its potential to second order in
size/|x| (MacCullagh's formula; Hughes, "Spacecraft Attitude Dynamics", ch. 8; Schaub &
Junkins, "Analytical Mechanics of Space Systems", gravity-gradient torque):

    V = −μ m / r − μ/(2 r³) (tr I − 3 r̂ᵀ I_w r̂),   r = |x|, r̂ = x/r, I_w = R I Rᵀ   (§9.7)

The force on the centre of mass is F = −∂V/∂x (V's gradient written out with one division
per evaluation; force and torque derive from one potential, so the total energy
E_total = T + V and the total angular momentum L_total = m x × v + R (I ω + h) are exact
invariants of the equations: tests/physics/test_central_gravity.py checks both identities);
the torque about the centre of mass is τ = (3 μ / r³) ρ̂ × (I ρ̂), ρ̂ = Rᵀ r̂ (body frame).
Outputs: r_orbit (m) and L_total (N·m·s, world, about the central body).

`read_central_gravity` reads ``[central_gravity] mu`` (Earth's by default) of a scene with
``features.central_gravity`` and refuses the combinations the model does not cover;
`FEATURE` declares it all (modelsrc.feature).
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ..assembly import Assembly
from ..feature import Builder, Feature, FeatureDoc, Outputs, Phase, Reader, ReadStage, SceneRead
from ..methods import RIGID_FLOW_METHODS
from ..nominal_floors import checked_magnitude
from ..quaternion import reciprocal
from ..scene_data import SceneData
from ..scene_reader import SceneReader
from ..variables import vector_names

MU_EARTH = 3.986004418e14  # m³/s²: Earth's G M (IERS Conventions 2010, table 1.1; WGS 84)

# Features a body in the central field cannot have, and why (docs/theory.md §9.7).
EXCLUDED_FEATURES = {
    "gravity": "the uniform field g and the central field are two models of one gravity: choose one",
    "orbit": "features.orbit prescribes a circular orbit of the centre of mass; in the central field the centre "
    "of mass flies its own (Keplerian) orbit",
}


def read_central_gravity(
    rd: SceneReader, features: frozenset[str], init: dict[str, Any], fields: dict[str, Any]
) -> float:
    """μ (m³/s², finite, > 0; MU_EARTH when [central_gravity] mu is not given) when
    features.central_gravity is true, else 0.0. Refuses the feature without translation,
    with any of EXCLUDED_FEATURES, a start position at the central body (|x_cm| not above
    the body's size ℓ = sqrt(tr I / m): the range of the centre of mass in the field, checked
    again by the FMU at initialisation), and a [central_gravity] table without the feature."""
    sec = rd.feature_section("central_gravity", features, EXCLUDED_FEATURES)
    if sec is None:
        return 0.0
    if "translation" not in features:
        raise rd.fail(
            "features.central_gravity",
            "needs features.translation = true (the central field pulls the centre of mass, which moves only in "
            "free flight; for a prescribed circular orbit use features.orbit)",
        )
    x0 = rd.vector("initial.x_cm", init["x_cm"], 3) if "x_cm" in init else np.zeros(3)
    if not np.any(x0 != 0.0):
        raise rd.fail(
            "initial.x_cm",
            "required and not at the origin when features.central_gravity is true: the central body sits at the "
            "world origin (m, world frame; about 7e6 in low Earth orbit)",
        )
    r0, ell = float(np.hypot.reduce(x0)), radius_of_gyration(np.trace(fields["inertia"]), fields["mass"])
    if not r0 > ell:
        raise rd.fail("initial.x_cm", f"{at_the_central_body(r0, ell)} (m, world frame; about 7e6 in low Earth orbit)")
    return rd.number("central_gravity.mu", sec.get("mu", MU_EARTH), positive=True)


def radius_of_gyration(trace_I: float, mass: float) -> float:
    """ℓ = sqrt(tr I / m) (m), the body's size, without overflow or underflow (both ≥ 1e-100, §2.3)."""
    return math.sqrt(trace_I) / math.sqrt(mass)


def at_the_central_body(r: float, ell: float) -> str:
    """The refusal of a centre of mass within the body's own size of the central body (§9.7)."""
    return (
        f"|x_cm| = {r:g} is not above the body's size sqrt(tr I / m) = {ell:g} m: the body is at the central body "
        "(MacCullagh's formula of docs/theory.md §9.7 holds for |x_cm| >> the body's size)"
    )


def add_central_gravity(a: Assembly) -> None:
    """The parameter mu (m³/s², > 0), the force −∂V/∂x_cm (N, world, V's gradient written out)
    and the torque (3μ/r³) ρ̂ × (I ρ̂) (N·m, body) of the central field; the body's potential
    becomes V (§9.7)."""
    if not a.scene.has("central_gravity"):
        return
    x = a.position  # the centre of mass: central_gravity needs translation (free flight made it and the mass)
    assert x is not None and a.mass is not None
    mu = ca.SX.sym("mu")
    a.parameter(mu, ["mu"], [a.scene.mu], "m3/s2", ["gravitational parameter G M of the central body at the origin"])
    a.checks.append(("mu must be > 0 (G M of the central body, m^3/s^2)", mu, True))
    # the range of the centre of mass in the field: |x_cm| above the body's size ℓ (§9.7); below
    # it the body is at the central body and |x|³ of the field may underflow to 0 (issue 39.2, 39.8)
    a.checks.append(
        (
            "|x_cm| must be > the body's size sqrt(tr I / m): the body is at the central body (MacCullagh's "
            "formula, docs/theory.md §9.7, holds for |x_cm| >> the body's size)",
            ca.dot(x, x) - ca.trace(a.inertia) / a.mass,
            True,
        )
    )
    V = potential(x, a.rotation.T @ x, a.inertia, a.mass, mu)
    a.potential = V
    a.potential_field = "the central field (docs/theory.md §9.7)"
    a.rates_in_nominal_units = True  # the body turns at about its orbit rate (§9.7)
    rho = a.rotation.T @ x  # the body-frame position: ρ̂ = ρ / r
    I_rho = a.inertia @ rho
    # 1/r² as one division reused (quaternion.reciprocal: CasADi turns a·(1/s) into a/s), μ/r³
    # and 3μ/r⁵ from it: the gradient CasADi takes of V has ~10 divisions per evaluation
    inv_r2 = reciprocal(ca.dot(x, x))
    g3 = mu * inv_r2 * ca.sqrt(inv_r2)
    g5 = 3 * g3 * inv_r2
    # F = −∂V/∂x written out (§9.7): −(μ/r³) (m + (3/2) tr I / r² − (15/2) ρᵀIρ / r⁴) x − (3μ/r⁵) R (I ρ)
    radial = g3 * (a.mass + inv_r2 * (1.5 * ca.trace(a.inertia) - 7.5 * ca.dot(rho, I_rho) * inv_r2))
    a.force_world = a.force_world - (radial * x + g5 * (a.rotation @ I_rho))
    # τ = (3μ/r³) ρ̂ × (I ρ̂) = 3μ ρ × (I ρ) / r⁵ (§9.7)
    a.torque = a.torque + g5 * ca.cross(rho, I_rho)


def potential(x: ca.SX, rho: ca.SX, I: ca.SX, m: ca.SX, mu: ca.SX) -> ca.SX:
    """V (J) of MacCullagh's formula: −μ m/r − μ/(2 r³) (tr I − 3 ρ̂ᵀ I ρ̂), x the centre of mass
    (m, world, from the central body), ρ = Rᵀ x the same vector in the body frame (ρ̂ᵀ I ρ̂ =
    r̂ᵀ I_w r̂), I about the centre of mass (kg·m², body), m (kg), μ (m³/s²) (§9.7)."""
    r2 = ca.dot(x, x)
    r = ca.sqrt(r2)
    return -mu * m / r - mu / (2 * r2 * r) * (ca.trace(I) - 3 * ca.dot(rho, I @ rho) / r2)


def central_outputs(a: Assembly, w_dot: ca.SX) -> list[tuple[str, ca.SX, str | None, str]]:
    """r_orbit (m) and L_total (N·m·s, world): m x × v + R (I ω + h), the angular momentum
    about the central body, conserved with the rotors' motors idle and no inputs (§9.7).
    Empty without central_gravity."""
    if not a.scene.has("central_gravity"):
        return []
    x, v = a.position, a.velocity
    assert x is not None and v is not None and a.mass is not None
    L = a.mass * ca.cross(x, v) + a.rotation_matrix @ (a.inertia_cm @ a.omega + a.internal_momentum())
    out: list[tuple[str, ca.SX, str | None, str]] = [
        ("r_orbit", ca.norm_2(x), "m", "distance of the centre of mass from the central body")
    ]
    for k, name in enumerate(vector_names("L_total", 3)):
        desc = f"total angular momentum about the central body (orbit m x_cm x v_cm + spin), world axis {k + 1}"
        out.append((name, L[k], "N.m.s", desc))
    return out


def central_nominals(scene: SceneData, out: dict[str, float]) -> None:
    """In a central field ω is measured against the orbit rate sqrt(μ/r0³) at the start
    distance r0 = |x0|, as in an orbit (docs/theory.md §9.7)."""
    if scene.has("central_gravity"):
        n0 = math.sqrt(scene.mu / float(np.linalg.norm(scene.x0)) ** 3)
        out["w_body"] = checked_magnitude(
            scene, "the orbit rate sqrt(mu / |x_cm|^3)", max(float(np.linalg.norm(scene.w0)), n0)
        )


def _read(ctx: SceneRead) -> dict[str, Any]:
    return {
        "mu": read_central_gravity(ctx.rd, ctx.features, ctx.initial, ctx.fields)
    }  # its feature rules before the start's


def _doc(scene: SceneData) -> FeatureDoc | None:
    """The central field's potential, force and torque, and L_total (§9.7)."""
    if not scene.has("central_gravity"):
        return None
    eq = (
        "V = −μ m/r − μ/(2 r³) (tr I − 3 ρ̂ᵀ I ρ̂);  M v̇_cm += −∂V/∂x_cm;  τ += (3μ/r³) ρ̂ × (I ρ̂),  ρ̂ = R(q)ᵀ x_cm/r",
        "§9.7 (MacCullagh; Hughes ch. 8; Schaub & Junkins)",
    )
    kept = ("the total angular momentum L_total = M x_cm × v_cm + L_world (orbit and spin, §9.7)",)
    return FeatureDoc(f"a central field, G M = {scene.mu:g} m³/s² at the origin", (eq,), kept)


FEATURE = Feature(
    name="central_gravity",
    doc=_doc,
    order=80,
    flags=("central_gravity",),
    tables={"central_gravity": frozenset({"mu"})},
    readers=(Reader(ReadStage.START, 10, _read),),
    # the splittings' flows are those of a body without position-dependent torques (docs/theory.md §5.3, §7.4)
    excluded_methods=RIGID_FLOW_METHODS,
    excluded_why="in a central field they are refused: their flows have no position-dependent force and torque",
    excludes_methods=lambda features, fields: "central_gravity" in features,
    # its gravity-gradient torque (docs/theory.md §9.7); conservative: E_total is kept
    torque_flags=frozenset({"central_gravity"}),
    builders=(Builder(Phase.PARAMETERS, 40, add_central_gravity),),
    always=Outputs(60, central_outputs),  # after the requested outputs: r_orbit, L_total last (§9.7)
    nominals=central_nominals,
)
