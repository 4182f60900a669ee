"""The moving reference point as one feature: free flight, forces at body points, the moving pivot.

The general motion of a rigid body is a translation of its centre of mass superposed
with a rotation about it (Marin, "Analytical dynamics"; docs/theory.md §7). Three
features move the point the body turns about:

* ``translation`` (free flight): states x_cm, v_cm (m, m/s, world), Newton's law
  M a_C = Σ F (MIT 2.003J, "Linear momentum for rigid bodies"), the body turning about
  its centre of mass; inputs f_body, f_world (N) at the centre of mass
  (``force_body``, ``force_world``), uniform gravity M g with ``gravity``;
* force points ``[forces.<name>]``: an input f_<name> (N, body or world frame) at the
  body point r_<name> (m, body, from the centre of mass) adds its force and its moment
  r × F;
* ``moving_pivot``: the pivot of a heavy top follows the prescribed acceleration
  a_pivot (m/s², world); states x_pivot, v_pivot; Euler's equations about the moving
  point (MIT 2.003J, "Angular momentum for rigid bodies", ``rigid_body.moving_pivot_torque``).

Each builder adds its symbols, variables and terms to an ``assembly.Assembly`` (the
reference point's position, velocity and acceleration are the body's, shared; the force
inputs are this feature's own record); `FEATURE` declares them (modelsrc.feature). A scene
without these features gets none of their variables.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ... import rigid_body as rb
from ...assembly import Assembly, StatePart
from ...feature import (
    Builder,
    Feature,
    FeatureDoc,
    Output,
    OutputContext,
    OutputValue,
    Phase,
    Reader,
    ReadStage,
    SceneRead,
)
from ...nominal_floors import W_FLOOR, body_size, checked_magnitude
from ...scene_data import SceneData
from ...variables import Kind, vector_names
from .scene_file import RESERVED_POINT_NAMES, check_feature_rules, read_force_points, read_start

AXES = (1, 2, 3)
# Features that move the reference point (centre of mass or pivot): their states follow q, w_body.
MOTION_FLAGS = frozenset({"translation", "moving_pivot"})


@dataclass
class MotionSymbols:
    """This feature's own symbols: force point name -> its input symbol (N, in its frame),
    and the state part of the reference point's velocity (its rate is the acceleration)."""

    force_inputs: dict[str, ca.SX] = field(default_factory=dict)
    velocity_part: StatePart | None = None


def symbols(a: Assembly) -> MotionSymbols:
    """The moving reference point's record in the assembly."""
    return a.feature_state("free_motion", MotionSymbols)


def add_motion_states(a: Assembly) -> None:
    """x_cm, v_cm (free body) or x_pivot, v_pivot (moving pivot), after q and w_body:
    position (m) and velocity (m/s) of the reference point, world frame."""
    sc = a.scene
    if sc.has("translation"):
        base, what = "cm", "centre of mass"
    elif sc.has("moving_pivot"):
        base, what = "pivot", "pivot"
    else:
        return
    a.position, a.velocity = ca.SX.sym(f"x_{base}", 3), ca.SX.sym(f"v_{base}", 3)
    # ẋ = v, v̇ = a (docs/theory.md §7.1, §7.3): v̇ once the acceleration is known (`finish`);
    # positions and velocities never act back on the rotation (§7.4)
    velocity = symbols(a).velocity_part = StatePart(f"v_{base}", a.velocity, rotational=False)
    a.state_parts += [StatePart(f"x_{base}", a.position, rotational=False, rate=a.velocity), velocity]
    a.add(
        vector_names(f"x_{base}", 3),
        Kind.STATE,
        list(sc.x0),
        "m",
        [f"position of the {what}, world axis {i}" for i in AXES],
    )
    a.add(
        vector_names(f"v_{base}", 3),
        Kind.STATE,
        list(sc.v0),
        "m/s",
        [f"velocity of the {what}, world axis {i}" for i in AXES],
    )


def _force_input(a: Assembly, name: str, frame: str, where: str) -> ca.SX:
    """An input force vector (N) in `frame`; its symbol joins u, its variables the table."""
    sym = ca.SX.sym(name, 3)
    a.input_blocks.append(sym)
    a.add(
        vector_names(name, 3),
        Kind.INPUT,
        list(a.scene.input_start(name)),
        "N",
        [f"applied force {where}, {frame} axis {i}" for i in AXES],
    )
    return sym


def add_motion_inputs(a: Assembly) -> None:
    """f_body (N, body) and f_world (N, world) at the centre of mass, then one input
    f_<name> per force point (its moment is added with its point, `add_force_points`), then
    a_pivot (m/s², world): the prescribed acceleration of a moving pivot."""
    sc = a.scene
    if sc.has("force_body"):
        a.force_body = a.force_body + _force_input(a, "f_body", "body", "at the centre of mass")
    if sc.has("force_world"):
        a.force_world = a.force_world + _force_input(a, "f_world", "world", "at the centre of mass")
    for name, fp in sc.force_points.items():
        symbols(a).force_inputs[name] = _force_input(a, f"f_{name}", fp.frame, f"at point r_{name}")
    if not sc.has("moving_pivot"):
        return
    a.pivot_acceleration = ca.SX.sym("a_pivot", 3)
    a.input_blocks.append(a.pivot_acceleration)
    a.add(
        vector_names("a_pivot", 3),
        Kind.INPUT,
        list(sc.input_start("a_pivot")),
        "m/s2",
        [f"prescribed acceleration of the pivot, world axis {i}" for i in AXES],
    )


def add_moving_pivot_dynamics(a: Assembly) -> None:
    """The heavy top about a pivot accelerating at a_pivot: torque r_cm × Rᵀ M (g − a_pivot)
    and the potential −M g·(x_pivot + R r_cm) of the centre of mass (docs/theory.md §7.3).
    Runs after the heavy top's mass, r_cm and g exist (modelsrc.features.gravity, which
    leaves the torque of a moving pivot to this)."""
    if a.pivot_acceleration is None:
        return
    assert a.r_cm is not None and a.mass is not None and a.gravity is not None  # moving_pivot needs gravity
    assert a.position is not None  # add_motion_states made it
    a.torque = a.torque + rb.moving_pivot_torque(a.rotation, a.r_cm, a.mass, a.gravity, a.pivot_acceleration)
    a.potential = -a.mass * ca.dot(a.gravity, a.position + a.rotation_matrix @ a.r_cm)


def add_translation(a: Assembly) -> None:
    """Free flight: the mass, and uniform gravity M g at the centre of mass (no torque
    about it) with its potential −M g·x_cm (docs/theory.md §7.1)."""
    sc = a.scene
    if not sc.has("translation"):
        return
    a.mass = ca.SX.sym("mass")
    a.parameter(a.mass, ["mass"], [sc.mass], "kg", ["mass of the body"])
    a.checks.append(("mass must be > 0", a.mass, True))
    if sc.has("gravity"):
        a.gravity = ca.SX.sym("g", 3)
        a.parameter(
            a.gravity,
            vector_names("g", 3),
            sc.g,
            "m/s2",
            [f"gravitational acceleration, world axis {i}" for i in AXES],
        )
        # the weight M g enters the acceleration as g itself (reference_acceleration)
        assert a.position is not None  # add_motion_states made it
        a.potential = -a.mass * ca.dot(a.gravity, a.position)


def add_force_points(a: Assembly) -> None:
    """Parameters r_<name> (m, body, from the centre of mass); each point's force pushes
    the centre of mass and turns the body by r × F (docs/theory.md §7.1). A point
    declared at the centre of mass keeps the scene torque-free (Scene.torque_free), so
    the FMU refuses to move it away from there."""
    for name, fp in a.scene.force_points.items():
        r = ca.SX.sym(f"r_{name}", 3)
        a.parameter(
            r,
            vector_names(f"r_{name}", 3),
            fp.point,
            "m",
            [f"application point of f_{name}, from the centre of mass, body axis {i}" for i in AXES],
        )
        f = symbols(a).force_inputs[name]
        f_body = f if fp.frame == "body" else a.rotation.T @ f  # body components Rᵀ f of a world force
        if fp.frame == "body":
            a.force_body = a.force_body + f
        else:
            a.force_world = a.force_world + f
        a.torque = a.torque + rb.force_moment(r, f_body)
        if np.any(fp.point != 0.0):
            continue
        a.checks.append(
            (
                f"force point '{name}' was declared at the centre of mass, so this FMU was built torque-free: "
                f"r_{name} must stay 0",
                -ca.norm_1(r),
                False,
            )
        )


def add_motion_parameters(a: Assembly) -> None:
    """The moving pivot's dynamics, then free flight's mass and gravity, then the force points."""
    add_moving_pivot_dynamics(a)
    add_translation(a)
    add_force_points(a)


def reference_acceleration(a: Assembly) -> None:
    """The acceleration (m/s², world) of the reference point, the rate of its velocity:
    M a_C = Σ F for a free body, the input a_pivot for a moving pivot (else it stays zero)."""
    if a.scene.has("translation"):
        assert a.mass is not None  # add_translation made it
        force = a.force_world if a.force_body.is_zero() else a.force_world + a.rotation @ a.force_body  # turned once
        # M a = M g + F: a = g + F/M, with 1/M once per parameter change (§7.1); no force but
        # the weight: the parabola a = g, which the step then takes from the parameters alone
        accel = ca.SX.zeros(3) if force.is_zero() else rb.newton_acceleration(force, a.derive("inv_mass", 1 / a.mass))
        a.acceleration = accel if a.gravity is None else a.gravity + accel
    elif a.pivot_acceleration is not None:
        a.acceleration = a.pivot_acceleration
    velocity = symbols(a).velocity_part
    if velocity is not None:
        velocity.rate = a.acceleration


def motion_outputs(a: Assembly, ctx: OutputContext) -> dict[str, OutputValue]:
    """Derived outputs of a moving reference point: name -> value:
    x_cm, v_cm, a_cm of the centre of mass (a moving pivot's from v = v_B + ω × r,
    a = a_B + ω̇ × r + ω × (ω × r), docs/theory.md §7.2), p = M v_cm, f_pivot, and
    E_kin = ½ M |v_cm|² + ½ ωᵀ I_cm ω, E_total = E_kin + potential (§7.1)."""
    if a.position is None or a.velocity is None or a.mass is None:
        return {}
    if a.scene.has("translation"):
        x_c, v_c, a_c = a.position, a.velocity, a.acceleration
    else:
        assert a.r_cm is not None  # the heavy top made it (moving_pivot needs gravity)
        R = a.rotation_matrix
        r_w, w_w = R @ a.r_cm, R @ a.omega
        x_c = a.position + r_w
        v_c = rb.point_velocity(w_w, r_w, a.velocity)
        a_c = rb.point_acceleration(w_w, R @ ctx.omega_dot, r_w, a.acceleration)
    # + what the features carry relative to the body (the rotors, docs/theory.md §8.2; 0
    # without): I_cm is the whole body's
    E_kin = (
        rb.translational_kinetic_energy(a.mass, v_c)
        + rb.kinetic_energy(a.inertia_cm, a.omega)
        + a.internal_energy(a.omega)
    )
    V = a.potential
    out = {
        "x_cm": OutputValue(x_c, "m", "position of the centre of mass, world axis {}"),
        "v_cm": OutputValue(v_c, "m/s", "velocity of the centre of mass, world axis {}"),
        "a_cm": OutputValue(a_c, "m/s2", "acceleration of the centre of mass, world axis {}"),
        "p": OutputValue(a.mass * v_c, "N.s", "linear momentum M v_cm, world axis {}"),
        "E_kin": OutputValue(E_kin, "J", "kinetic energy: translational + rotational about the centre of mass"),
        "E_total": OutputValue(E_kin + V if V is not None else E_kin, "J", f"kinetic + potential energy of "
                               f"{a.potential_field}"),
    }  # fmt: skip
    if a.scene.has("translation"):
        del out["x_cm"], out["v_cm"]  # the states themselves
    if a.gravity is not None and a.pivot_acceleration is not None:
        out["f_pivot"] = OutputValue(
            rb.pivot_force(a.mass, a_c, a.gravity), "N", "force the pivot supplies, world axis {}"
        )
    return out


def motion_input_names(scene: SceneData) -> list[str]:
    """f_body, f_world, f_<point> per force point and a_pivot, those the scene has, in
    value-reference order."""
    names = [n for f, n in (("force_body", "f_body"), ("force_world", "f_world")) if scene.has(f)]
    names += [f"f_{n}" for n in scene.force_points]
    return names + (["a_pivot"] if scene.has("moving_pivot") else [])


def motion_nominals(scene: SceneData, out: dict[str, float]) -> None:
    """A position's nominal is its start distance, at least the body's size ℓ (m); a
    velocity's its start speed, at least ℓ·W_FLOOR (m/s) (docs/theory.md §5.5)."""
    if not scene.features & MOTION_FLAGS:
        return
    base = "cm" if scene.has("translation") else "pivot"
    size = checked_magnitude(scene, f"the body's size sqrt(tr I / m) (mass {scene.mass:g} kg)", body_size(scene))
    x = checked_magnitude(scene, f"|initial.x_{base}|", float(np.linalg.norm(scene.x0)))
    v = checked_magnitude(scene, f"|initial.v_{base}|", float(np.linalg.norm(scene.v0)))
    out[f"x_{base}"] = max(x, size)
    out[f"v_{base}"] = checked_magnitude(scene, f"the body's size times {W_FLOOR} rad/s", max(v, size * W_FLOOR))


def _read_start(ctx: SceneRead) -> dict[str, Any]:
    out: dict[str, Any] = dict(read_start(ctx.rd, ctx.features, ctx.initial))
    out["force_points"] = read_force_points(ctx.rd, ctx.features, RESERVED_POINT_NAMES)
    return out


def _check_rules(ctx: SceneRead) -> dict[str, Any]:
    check_feature_rules(ctx.rd, ctx.features)
    return {}


def _doc(scene: SceneData) -> FeatureDoc | None:
    """Free flight, forces at body points, the moving pivot (§7.1, §7.3)."""
    eqs = []
    if scene.has("translation"):
        eqs.append(("ẋ_cm = v_cm,  M v̇_cm = f_world + R f_body + Σ F_i (+ M g)  (world)", "§7.1 (MIT 2.003J)"))
    if scene.force_points:
        eqs.append(("force F_i at the body point r_i: τ += r_i × F_i (body)", "§7.1"))
    if scene.has("moving_pivot"):
        eqs.append(("I_B ω̇ + ω × I_B ω = r_C × Rᵀ M (g − a_B),  ẋ_B = v_B, v̇_B = a_B (input)", "§7.3 (MIT 2.003J)"))
    what = [w for flag, w in (("translation", "free flight of the centre of mass"), ("moving_pivot", "a moving pivot"))
            if scene.has(flag)]  # fmt: skip
    if scene.force_points:
        what.append(f"forces at body points ({', '.join(scene.force_points)})")
    return FeatureDoc(", ".join(what), tuple(eqs)) if eqs else None


FEATURE = Feature(
    name="free_motion",
    doc=_doc,
    order=50,
    flags=("translation", "force_body", "force_world", "moving_pivot"),
    tables={"forces": None},
    start_keys=lambda data: frozenset({"x_cm", "v_cm", "x_pivot", "v_pivot"}),
    needs_mass=("translation",),
    readers=(Reader(ReadStage.RULES, 10, _check_rules), Reader(ReadStage.START, 20, _read_start)),
    input_of_flag={"force_body": "f_body", "force_world": "f_world", "moving_pivot": "a_pivot"},
    file_inputs=lambda fields: frozenset(f"f_{n}" for n in fields["force_points"]),
    # a moving pivot's force turns the body, so does a force point off the centre of mass;
    # forces through the centre of mass (force_body, force_world) push without turning (§7.1)
    torque_flags=frozenset({"moving_pivot"}),
    adds_torque=lambda scene: (
        scene.has("moving_pivot") or any(np.any(fp.point != 0.0) for fp in scene.force_points.values())
    ),
    working_flags=frozenset({"force_body", "force_world", "moving_pivot"}),
    does_work=lambda scene: (
        bool(scene.features & {"force_body", "force_world", "moving_pivot"}) or bool(scene.force_points)
    ),
    motion_flags=MOTION_FLAGS,
    # forces that turn with the body over a step (§7.4)
    blocks_exact_flow=lambda scene: (
        scene.has("force_body") or any(fp.frame == "body" for fp in scene.force_points.values())
    ),
    input_names=motion_input_names,
    builders=(
        Builder(Phase.STATES, 10, add_motion_states),
        Builder(Phase.INPUTS, 20, add_motion_inputs),
        Builder(Phase.PARAMETERS, 20, add_motion_parameters),
    ),
    finish=reference_acceleration,
    outputs=(
        Output("x_cm", 30, MOTION_FLAGS),
        Output("v_cm", 30, MOTION_FLAGS),
        Output("a_cm", 30, MOTION_FLAGS),
        Output("p", 30, MOTION_FLAGS),
        Output("f_pivot", 30, frozenset({"moving_pivot"})),
    ),
    requested=motion_outputs,
    nominals=motion_nominals,
)
