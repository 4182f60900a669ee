"""The circular orbit as one feature (``orbit``, ``gravity_gradient``): orbit angle and rate, gravity gradient, LVLH.

Conventions (docs/theory.md §9; Hughes, "Spacecraft Attitude Dynamics", ch. 8): the
centre of mass moves on a circular orbit of rate n (rad/s). The orbit frame LVLH has
x along-track, z to nadir (towards the central body) and y = z × x = −orbit normal;
it turns at ω_o = −n e_y (its own y axis, fixed in inertial space). The world frame
is the inertial frame that coincides with LVLH at t = 0, so at orbit angle θ = n t

    R_wo(θ) = R_y(−θ):   nadir c_w = (−sin θ, 0, cos θ),   orbit normal o_w = (0, −1, 0)    (§9.1)

The state θ (`orbit_angle`, θ̇ = n) makes the right-hand side autonomous (the generated
steps take no time argument). With gravity_gradient the body feels
τ = 3 n² ĉ × (I ĉ), ĉ = Rᵀ c_w the nadir in the body frame (§9.2), and the Jacobi integral
E_J = ½ ω_rᵀ I ω_r − ½ n² ôᵀ I ô + (3/2) n² ĉᵀ I ĉ (ω_r = ω − n ô, ô = Rᵀ o_w; with
rotors their relative terms, `Assembly.internal_energy`) is conserved (§9.3).

`read_orbit` reads ``[orbit] rate`` of a scene with ``features.orbit`` and refuses the
feature combinations the orbit model does not cover; `FEATURE` declares it all
(modelsrc.feature).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from .. import unit_mistakes
from ..assembly import Assembly, StatePart
from ..feature import Builder, Feature, FeatureDoc, Outputs, Phase, Reader, ReadStage, SceneRead
from ..methods import RIGID_FLOW_METHODS
from ..quaternion import quat_mul
from ..scene_data import SceneData
from ..scene_reader import SceneReader
from ..variables import Kind, vector_names

# Features an orbiting body cannot have, and why. The orbit is a prescribed circular motion
# of the centre of mass (docs/theory.md §9.1): a free centre of mass (translation) flies
# its own orbit in features.central_gravity (§9.7), a pivot (gravity: the heavy top's uniform
# field, moving_pivot) has no meaning in free fall, and a prescribed rate holds ω, which
# the gravity-gradient torque would have to be absorbed against.
EXCLUDED_FEATURES = {
    "translation": "the centre of mass follows the prescribed circular orbit; for a free centre of mass in a "
    "central field (a Keplerian orbit) use features.central_gravity instead of features.orbit",
    "moving_pivot": "an orbiting body turns about its centre of mass, it has no pivot",
    "gravity": "the uniform field of a heavy top about a pivot has no meaning in free fall; the orbit's "
    "gravity acts through features.gravity_gradient",
    "prescribed_rate": "it holds omega at its start value against the orbit's torques (tau_bearing does not "
    "include them)",
}


def read_orbit(rd: SceneReader, features: frozenset[str]) -> float:
    """The orbit rate n (rad/s, finite and > 0) of [orbit] rate when features.orbit is
    true, else 0.0; refuses gravity_gradient without orbit, an [orbit] table without the
    feature, and orbit with any of EXCLUDED_FEATURES."""
    if "gravity_gradient" in features and "orbit" not in features:
        raise rd.fail(
            "features.gravity_gradient",
            "needs features.orbit = true (the torque 3 n^2 c x (I c) needs the orbit rate n and the nadir c)",
        )
    sec = rd.feature_section("orbit", features, EXCLUDED_FEATURES)
    if sec is None:
        return 0.0
    if "rate" not in sec:
        raise rd.fail(
            "orbit.rate",
            "required when features.orbit is true: the orbit rate n = 2 pi / period (rad/s, finite, > 0; "
            "about 1.1e-3 in low Earth orbit)",
        )
    n = rd.number("orbit.rate", sec["rate"], positive=True)
    unit_mistakes.orbit_rate(f"scene file {rd.path}: field 'orbit.rate'", n)
    return n


# The range of the orbit angle θ (rad, docs/robustness.md §2, Ranges). θ enters only through
# sin θ and cos θ, so a start angle means its value mod 2π; but θ advances by n h per
# internal step, and a double near |θ| resolves |θ|·2.2e-16 rad: at 1e6 rad that is 2.2e-10
# rad, so an advance of 1e-6 rad (n = 1.1e-3 rad/s of low Earth orbit, h = 1 ms) is carried
# to 2e-4 relative; at 1e17 rad (issue 39.6) the resolution is 22 rad and θ never moves.
# 1e6 rad is 160,000 orbits, 1e9 s of a low Earth orbit: no run starts or gets beyond it.
ORBIT_ANGLE_MAX = 1e6


@dataclass
class OrbitSymbols:
    """The orbit's own symbols: the orbit angle θ (rad, a state) and its state part, and
    the rate n (rad/s, a parameter)."""

    angle: ca.SX
    part: StatePart
    rate: ca.SX | None = None


def symbols(a: Assembly) -> OrbitSymbols | None:
    """The orbit's record in the assembly, None without features.orbit."""
    state: OrbitSymbols | None = a.feature_states.get("orbit")
    return state


def add_orbit_state(a: Assembly) -> None:
    """orbit_angle θ (rad): the orbit's angle n t from the start (θ̇ = n), the last state."""
    if not a.scene.has("orbit"):
        return
    angle = ca.SX.sym("orbit_angle")
    part = StatePart("orbit_angle", angle, rotational=True)  # the gravity-gradient torque depends on it (§9)
    a.feature_states["orbit"] = OrbitSymbols(angle, part)
    a.state_parts.append(part)
    a.rates_in_nominal_units = True  # the body turns at about n (§9.1)
    a.add(["orbit_angle"], Kind.STATE, [0.0], "rad", ["orbit angle n*t travelled since the start (LVLH = world at 0)"])


def add_orbit(a: Assembly) -> None:
    """The parameter n_orbit (rad/s, > 0) and, with gravity_gradient, the torque
    3 n² ĉ × (I ĉ) about the centre of mass (docs/theory.md §9.2)."""
    orbit = symbols(a)
    if orbit is None:
        return
    n = ca.SX.sym("n_orbit")
    a.parameter(n, ["n_orbit"], [a.scene.orbit_rate], "rad/s", ["orbit rate n = 2 pi / orbital period (circular)"])
    a.checks.append(("n_orbit must be > 0 (the rate of a circular orbit, rad/s)", n, True))
    a.checks.append(
        (
            f"|orbit_angle| must be <= {ORBIT_ANGLE_MAX:g} rad (beyond it the angle's resolution, |angle| * 2.2e-16, "
            "is too coarse for an internal step's advance n h to move it: start it within one orbit, its value "
            "mod 2 pi)",
            ORBIT_ANGLE_MAX - ca.fabs(orbit.angle),
            False,
        )
    )
    orbit.rate = n
    orbit.part.rate = n  # θ̇ = n (§9.1)
    if a.scene.has("gravity_gradient"):
        # the torque depends on θ through sin θ and cos θ only: symbols for them, so that a
        # fixed step can take them by angle addition (Assembly.clock, modelsrc.integrators.Clock)
        s, co = ca.SX.sym("sin_orbit_angle"), ca.SX.sym("cos_orbit_angle")
        a.clock = (orbit.angle, n, s, co)
        c = nadir_from(a, s, co)
        if a.inertia.sparsity().is_diag():  # principal axes: the rates take it with derived coefficients
            a.principal_terms.append(GravityGradient(a, n, c))  # (model.principal_rates, the gyrostat's)
        else:
            a.torque = a.torque + gravity_gradient_torque(a, n, c)


def gravity_gradient_torque(a: Assembly, n: ca.SX, c: ca.SX) -> ca.SX:
    """3 n² ĉ × (I ĉ) (N·m, body), ĉ the nadir in the body frame, n the orbit rate
    (docs/theory.md §9.2)."""
    return 3 * n**2 * ca.cross(c, a.inertia @ c)


@dataclass
class GravityGradient:
    """The gravity gradient kept out of the torque on principal axes (`Assembly.principal_terms`)."""

    a: Assembly
    n: ca.SX
    nadir: ca.SX

    def torque(self) -> ca.SX:
        """3 n² ĉ × (I ĉ) (N·m, body), with the inertia as it is when asked."""
        return gravity_gradient_torque(self.a, self.n, self.nadir)

    def acceleration(self, coeff: ca.SX, prefix: str) -> ca.SX:
        """The gravity gradient's angular acceleration on principal axes (rad/s², body):
        3 n² ĉ × (I ĉ) / M_i = −3 n² k_i ĉ_j ĉ_k (i, j, k cyclic) with the Euler coefficients
        k_i = (I_j − I_k)/M_i (`coeff`, expressions of p), −3 n² k derived once under
        `prefix` + "gravity_gradient_coeff" (docs/theory.md §9.2)."""
        gg = self.a.derive(prefix + "gravity_gradient_coeff", -3 * self.n**2 * coeff)
        c = self.nadir
        return ca.vertcat(*[gg[i] * (c[(i + 1) % 3] * c[(i + 2) % 3]) for i in range(3)])


def nadir_body(a: Assembly, th: ca.SX) -> ca.SX:
    """ĉ (body frame): the unit vector to nadir at orbit angle θ, Rᵀ (−sin θ, 0, cos θ) (§9.1)."""
    return nadir_from(a, ca.sin(th), ca.cos(th))


def nadir_from(a: Assembly, sin_th: ca.SX, cos_th: ca.SX) -> ca.SX:
    """ĉ (body frame) from sin θ and cos θ of the orbit angle: Rᵀ (−sin θ, 0, cos θ) (§9.1)."""
    return a.rotation.T @ ca.vertcat(-sin_th, 0, cos_th)


def orbit_normal_body(a: Assembly) -> ca.SX:
    """ô (body frame): the orbit normal −e_y of the world frame, Rᵀ (0, −1, 0) (§9.1)."""
    return a.rotation.T @ ca.SX([0.0, -1.0, 0.0])


def roll_pitch_yaw(R: ca.SX) -> ca.SX:
    """(roll φ, pitch θ, yaw ψ) in rad of R = R_z(ψ) R_y(θ) R_x(φ) (body -> LVLH, the 3-2-1
    sequence: yaw about z, then pitch about y, then roll about x; §9.4). θ ∈ [−π/2, π/2]."""
    roll = ca.atan2(R[2, 1], R[2, 2])
    pitch = ca.atan2(-R[2, 0], ca.sqrt(R[2, 1] ** 2 + R[2, 2] ** 2))
    yaw = ca.atan2(R[1, 0], R[0, 0])
    return ca.vertcat(roll, pitch, yaw)


def orbit_outputs(a: Assembly, w_dot: ca.SX) -> list[tuple[str, ca.SX, str | None, str]]:
    """(name, expression, unit, description) of the outputs relative to the orbit frame
    (§9.4): q_lvlh, rpy_lvlh, w_lvlh, nadir_body and E_jacobi (§9.3)."""
    orbit = symbols(a)
    if orbit is None or orbit.rate is None:
        return []
    th, n = orbit.angle, orbit.rate
    # q_ow = conj(q_wo), q_wo = (cos(θ/2), 0, −sin(θ/2), 0): R_y(−θ)
    q_ow = ca.vertcat(ca.cos(th / 2), 0, ca.sin(th / 2), 0)
    q_lvlh = quat_mul(q_ow, a.quaternion)
    R_wo_T = ca.vertcat(
        ca.horzcat(ca.cos(th), 0, ca.sin(th)), ca.horzcat(0, 1, 0), ca.horzcat(-ca.sin(th), 0, ca.cos(th))
    )
    c, o = nadir_body(a, th), orbit_normal_body(a)
    w_rel = a.omega - n * o
    E = 0.5 * ca.dot(w_rel, a.inertia @ w_rel) - 0.5 * n**2 * ca.dot(o, a.inertia @ o)
    E = a.internal_energy(w_rel, E)  # the rotors' relative terms (§9.3)
    if a.scene.has("gravity_gradient"):
        E = E + 1.5 * n**2 * ca.dot(c, a.inertia @ c)
    out: list[tuple[str, ca.SX, str | None, str]] = []
    for name, expr, unit, desc in (
        ("q_lvlh", q_lvlh, None, "orientation quaternion body->LVLH, component {} (scalar first)"),
        (
            "rpy_lvlh",
            roll_pitch_yaw(R_wo_T @ a.rotation_matrix),
            "rad",
            "roll, pitch, yaw (3-2-1) relative to LVLH, angle {}",
        ),
        ("w_lvlh", w_rel, "rad/s", "angular velocity relative to LVLH, body axis {}"),
        ("nadir_body", c, None, "unit vector to nadir, body axis {}"),
    ):
        comps = "wxyz" if name == "q_lvlh" else ("roll", "pitch", "yaw") if name == "rpy_lvlh" else (1, 2, 3)
        for k, (nm, cmp) in enumerate(zip(vector_names(name, expr.shape[0]), comps)):
            out.append((nm, expr[k], unit, desc.format(cmp)))
    out.append(("E_jacobi", E, "J", "Jacobi integral: energy relative to the orbit frame (conserved, §9.3)"))
    return out


def orbit_nominals(scene: SceneData, out: dict[str, float]) -> None:
    """In an orbit the body turns at about n (~1e-3 rad/s in low orbit): ω is measured
    against n, not against W_FLOOR, which would leave its error uncontrolled; the orbit
    angle against one orbit, 2π (docs/theory.md §9.1)."""
    if scene.has("orbit"):
        out["w_body"] = max(float(np.linalg.norm(scene.w0)), scene.orbit_rate)
        out["orbit_angle"] = 2 * math.pi


def _read(ctx: SceneRead) -> dict[str, Any]:
    return {"orbit_rate": read_orbit(ctx.rd, ctx.features)}


def _doc(scene: SceneData) -> FeatureDoc | None:
    """The orbit frame, the gravity gradient and the Jacobi integral (§9.1–9.3)."""
    if not scene.has("orbit"):
        return None
    eqs = [("θ̇ = n;  LVLH = R_y(−θ) (x along-track, z nadir, y = −orbit normal), world = LVLH at t = 0", "§9.1")]
    if scene.has("gravity_gradient"):
        eqs.append(("τ += 3 n² ĉ × (I ĉ),  ĉ = R(q)ᵀ (−sin θ, 0, cos θ) the nadir", "§9.2 (Hughes ch. 8)"))
    motors = " with the motor torques u = 0" if any(not r.speed for r in scene.rotors.values()) else ""
    kept = (f"the Jacobi integral E_jacobi, the energy relative to the orbit frame{motors} (§9.3)",)
    what = f"a circular orbit, n = {scene.orbit_rate:g} rad/s" + (
        ", gravity gradient" if scene.has("gravity_gradient") else ""
    )
    return FeatureDoc(what, tuple(eqs), kept)


FEATURE = Feature(
    name="orbit",
    doc=_doc,
    order=70,
    flags=("orbit", "gravity_gradient"),
    tables={"orbit": frozenset({"rate"})},
    readers=(Reader(ReadStage.RULES, 20, _read),),  # its feature rules before the others' fields
    # the splittings' flows are those of (q, ω) of a rigid body in an inertial frame (docs/theory.md §5.3)
    excluded_methods=RIGID_FLOW_METHODS,
    excluded_why="in an orbit they are refused: their flows are the inertial rigid body's, without the orbit angle",
    excludes_methods=lambda features, fields: "orbit" in features,
    torque_flags=frozenset({"gravity_gradient"}),
    # the gravity-gradient torque works through the orbit's turning field: what it conserves
    # is the Jacobi integral E_jacobi in the orbit frame (docs/theory.md §9.3)
    working_flags=frozenset({"gravity_gradient"}),
    blocks_exact_flow=lambda scene: scene.has("orbit"),  # the exact flow is the inertial rigid body's
    builders=(Builder(Phase.STATES, 30, add_orbit_state), Builder(Phase.PARAMETERS, 30, add_orbit)),
    always=Outputs(20, orbit_outputs),
    nominals=orbit_nominals,
)
