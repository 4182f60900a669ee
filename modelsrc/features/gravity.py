"""Uniform gravity as one feature (``gravity``): the [gravity] table and the heavy top about its pivot.

About a fixed pivot (the heavy top) the body turns about the pivot: its inertia is
shifted there (parallel axes, docs/theory.md §3.2) and the weight m g at the centre of
mass r_cm gives the torque r_cm × Rᵀ m g and the potential −m g·R r_cm (§4.1). About a
moving pivot the moving reference point adds the torque of g − a_pivot instead
(modelsrc.features.free_motion, §7.3); on a free body (translation) gravity acts at the
centre of mass, no torque about it (free flight's, §7.1). The mass, r_cm and g are the
body's shared symbols. `FEATURE` declares it (modelsrc.feature).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from .. import rigid_body as rb
from ..assembly import Assembly
from ..feature import Builder, Feature, FeatureDoc, Phase, Reader, ReadStage, SceneRead
from ..inertia import inertia_conditions, parallel_axis_shift
from ..scene_data import SceneData
from ..scene_reader import SceneReader
from ..variables import vector_names


def read_gravity(rd: SceneReader, features: frozenset[str], grav: dict[str, Any]) -> dict[str, np.ndarray]:
    """[gravity] of a scene with features.gravity: g (m/s², world), and r_cm (m, body,
    pivot -> centre of mass) unless the body is free (translation: no pivot)."""
    free = "translation" in features
    if free and "r_cm" in grav:
        raise rd.fail(
            "gravity.r_cm",
            "a free body (features.translation) has no pivot; gravity acts at its centre of mass: give only g",
        )
    keys = ("g",) if free else ("r_cm", "g")
    for k in keys:
        if k not in grav:
            raise rd.fail(f"gravity.{k}", "required when features.gravity is true (3 numbers)")
    return {k: rd.vector(f"gravity.{k}", grav[k], 3) for k in keys}


def _read(ctx: SceneRead) -> dict[str, Any]:
    grav = ctx.rd.section("gravity")
    if "gravity" in ctx.features:
        return read_gravity(ctx.rd, ctx.features, grav)
    if grav:
        raise ctx.rd.fail("gravity", "given but features.gravity is not true")
    return {}


def add_gravity(a: Assembly) -> None:
    """Heavy top: rotation about the pivot, inertia shifted there (parallel axes), the
    torque and potential of gravity (docs/theory.md §4.1); about a moving pivot, gravity
    g − a_pivot (§7.3, added by the moving reference point). (Gravity on a free body:
    free flight's.)"""
    sc = a.scene
    if not sc.has("gravity") or sc.has("translation"):
        return
    m, r_cm, g = ca.SX.sym("mass"), ca.SX.sym("r_cm", 3), ca.SX.sym("g", 3)
    a.parameter(m, ["mass"], [sc.mass], "kg", ["mass of the body"])
    a.parameter(
        r_cm, vector_names("r_cm", 3), sc.r_cm, "m", [f"pivot -> centre of mass, body axis {i}" for i in (1, 2, 3)]
    )
    a.parameter(
        g, vector_names("g", 3), sc.g, "m/s2", [f"gravitational acceleration, world axis {i}" for i in (1, 2, 3)]
    )
    a.checks.append(("mass must be > 0", m, True))
    a.mass, a.r_cm, a.gravity = m, r_cm, g
    if sc.pivot_inertia is None:
        a.inertia = parallel_axis_shift(a.inertia, m, r_cm)
    else:  # given about the pivot: the centre of mass inertia it implies must be physical
        a.inertia_cm = a.inertia - parallel_axis_shift(ca.SX.zeros(3, 3), m, r_cm)
        a.checks += [
            (f"{t} (about the centre of mass: the tensor about the pivot minus m(|r_cm|^2 1 - r_cm r_cm^T))", e, st)
            for t, e, st in inertia_conditions(
                a.inertia_cm, [f"I_cm[{i},{j}]" for i in range(1, 4) for j in range(1, 4)]
            )
        ]
    if a.pivot_acceleration is None:
        a.torque = a.torque + rb.weight_torque(a.rotation, r_cm, a.derive("weight", m * g))
        a.potential = rb.potential_energy(a.rotation_matrix, r_cm, m, g)


def pivot_torque(scene: SceneData) -> bool:
    """Gravity turns the body about a pivot; on a free body it acts at the centre of mass."""
    return scene.has("gravity") and not scene.has("translation")


def _doc(scene: SceneData) -> FeatureDoc | None:
    """Uniform gravity: at the centre of mass of a free body (§7.1), else the heavy top's
    torque about its pivot and, about a fixed pivot, the vertical angular momentum (§4.1, §4.2)."""
    if not scene.has("gravity"):
        return None
    if scene.has("translation"):
        return FeatureDoc(
            "uniform gravity at the centre of mass", (("M v̇_cm += M g  (no torque about the centre of mass)", "§7.1"),)
        )
    eq = ("τ += r_cm × (R(q)ᵀ m g),  I shifted to the pivot (parallel axes)", "§4.1, §3.2")
    kept = (
        ()
        if scene.has("moving_pivot")
        else ("the vertical angular momentum L_world · g/|g| about the fixed pivot (§4.2)",)
    )
    return FeatureDoc("uniform gravity on a body about a pivot (the heavy top)", (eq,), kept)


FEATURE = Feature(
    name="gravity",
    doc=_doc,
    order=20,
    flags=("gravity",),
    tables={"gravity": frozenset({"r_cm", "g"})},
    needs_mass=("gravity",),
    readers=(Reader(ReadStage.MASS, 10, _read),),
    torque_flags=frozenset({"gravity"}),
    adds_torque=pivot_torque,
    builders=(Builder(Phase.PARAMETERS, 10, add_gravity),),
)
