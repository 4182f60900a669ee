"""Feature builders of the moving reference point: free flight, forces at body points, the moving pivot.

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

Each builder adds its symbols, variables and terms to an ``assembly.Assembly``; the
model's value-reference order is ``model.BUILDERS``. A scene without these features
gets none of their variables.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from . import rigid_body as rb
from .assembly import Assembly
from .rotors import rotor_energy
from .variables import Kind, vector_names

AXES = (1, 2, 3)


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
    a.pos, a.vel = ca.SX.sym(f"x_{base}", 3), ca.SX.sym(f"v_{base}", 3)
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
    a.u_parts.append(sym)
    a.add(
        vector_names(name, 3),
        Kind.INPUT,
        list(a.scene.input_start(name)),
        "N",
        [f"applied force {where}, {frame} axis {i}" for i in AXES],
    )
    return sym


def add_force_inputs(a: Assembly) -> None:
    """f_body (N, body) and f_world (N, world) at the centre of mass, then one input
    f_<name> per force point (its moment is added by add_force_points)."""
    sc = a.scene
    if sc.has("force_body"):
        a.force_body = a.force_body + _force_input(a, "f_body", "body", "at the centre of mass")
    if sc.has("force_world"):
        a.force = a.force + _force_input(a, "f_world", "world", "at the centre of mass")
    for name, fp in sc.force_points.items():
        a.force_inputs[name] = _force_input(a, f"f_{name}", fp.frame, f"at point r_{name}")


def add_pivot_input(a: Assembly) -> None:
    """a_pivot (m/s², world): the prescribed acceleration of a moving pivot."""
    if not a.scene.has("moving_pivot"):
        return
    a.a_pivot = ca.SX.sym("a_pivot", 3)
    a.u_parts.append(a.a_pivot)
    a.add(
        vector_names("a_pivot", 3),
        Kind.INPUT,
        list(a.scene.input_start("a_pivot")),
        "m/s2",
        [f"prescribed acceleration of the pivot, world axis {i}" for i in AXES],
    )


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
        a.g = ca.SX.sym("g", 3)
        a.parameter(
            a.g, vector_names("g", 3), sc.g, "m/s2", [f"gravitational acceleration, world axis {i}" for i in AXES]
        )
        # the weight M g enters the acceleration as g itself (reference_acceleration)
        assert a.pos is not None  # add_motion_states made it
        a.V = -a.mass * ca.dot(a.g, a.pos)


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
        f = a.force_inputs[name]
        f_body = f if fp.frame == "body" else a.rot.T @ f  # body components Rᵀ f of a world force
        if fp.frame == "body":
            a.force_body = a.force_body + f
        else:
            a.force = a.force + f
        a.tau = a.tau + rb.force_moment(r, f_body)
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


def add_moving_pivot_dynamics(a: Assembly) -> None:
    """The heavy top about a pivot accelerating at a_pivot: torque r_cm × Rᵀ M (g − a_pivot)
    and the potential −M g·(x_pivot + R r_cm) of the centre of mass (docs/theory.md §7.3).
    Called by model.add_gravity once mass, r_cm and g exist."""
    assert a.r_cm is not None and a.mass is not None and a.g is not None
    assert a.a_pivot is not None and a.pos is not None  # add_pivot_input, add_motion_states made them
    a.tau = a.tau + rb.moving_pivot_torque(a.rot, a.r_cm, a.mass, a.g, a.a_pivot)
    a.V = -a.mass * ca.dot(a.g, a.pos + a.R @ a.r_cm)


def reference_acceleration(a: Assembly) -> ca.SX:
    """Acceleration (m/s², world) of the reference point: M a_C = Σ F for a free body,
    the input a_pivot for a moving pivot, zero otherwise."""
    if a.scene.has("translation"):
        assert a.mass is not None  # add_translation made it
        force = a.force if a.force_body.is_zero() else a.force + a.rot @ a.force_body  # turned once
        # M a = M g + F: a = g + F/M, with 1/M once per parameter change (§7.1); no force but
        # the weight: the parabola a = g, which the step then takes from the parameters alone
        accel = ca.SX.zeros(3) if force.is_zero() else rb.newton_acceleration(force, a.derive("inv_mass", 1 / a.mass))
        return accel if a.g is None else a.g + accel
    if a.a_pivot is not None:
        return a.a_pivot
    return ca.SX.zeros(3)


def motion_outputs(a: Assembly, w_dot: ca.SX) -> dict[str, tuple[ca.SX, str, str]]:
    """Derived outputs of a moving reference point: name -> (expression, unit, description):
    x_cm, v_cm, a_cm of the centre of mass (a moving pivot's from v = v_B + ω × r,
    a = a_B + ω̇ × r + ω × (ω × r), docs/theory.md §7.2), p = M v_cm, f_pivot, and
    E_kin = ½ M |v_cm|² + ½ ωᵀ I_cm ω, E_total = E_kin + potential (§7.1)."""
    if a.pos is None or a.vel is None or a.mass is None:
        return {}
    if a.scene.has("translation"):
        x_c, v_c, a_c = a.pos, a.vel, a.accel
    else:
        assert a.r_cm is not None  # add_gravity made it (moving_pivot needs gravity)
        r_w, w_w = a.R @ a.r_cm, a.R @ a.w
        x_c = a.pos + r_w
        v_c = rb.point_velocity(w_w, r_w, a.vel)
        a_c = rb.point_acceleration(w_w, a.R @ w_dot, r_w, a.accel)
    # + the rotors' part (docs/theory.md §8.2; 0 without rotors): I_cm is the whole body's
    field = "the central field (docs/theory.md §9.7)" if a.scene.has("central_gravity") else "uniform gravity"
    E_kin = rb.translational_kinetic_energy(a.mass, v_c) + rb.kinetic_energy(a.I_cm, a.w) + rotor_energy(a)
    out = {
        "x_cm": (x_c, "m", "position of the centre of mass, world axis {}"),
        "v_cm": (v_c, "m/s", "velocity of the centre of mass, world axis {}"),
        "a_cm": (a_c, "m/s2", "acceleration of the centre of mass, world axis {}"),
        "p": (a.mass * v_c, "N.s", "linear momentum M v_cm, world axis {}"),
        "E_kin": (E_kin, "J", "kinetic energy: translational + rotational about the centre of mass"),
        "E_total": (E_kin + a.V if a.V is not None else E_kin, "J", f"kinetic + potential energy of {field}"),
    }
    if a.scene.has("translation"):
        del out["x_cm"], out["v_cm"]  # the states themselves
    if a.g is not None and a.a_pivot is not None:
        out["f_pivot"] = (rb.pivot_force(a.mass, a_c, a.g), "N", "force the pivot supplies, world axis {}")
    return out
