"""A prescribed rate as one feature (``prescribed_rate``): ω held at its start value, and the torque that holds it.

The body turns at a constant rate about a fixed axis: d/dt Rᵀ Ω = −ω × ω = 0, so ω̇ = 0
replaces Euler's equations (docs/theory.md §4.4), and the output tau_bearing is the
torque the bearings supply, R (I ω̇ + ω × I ω). `FEATURE` declares it (modelsrc.feature).
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from .. import rigid_body as rb
from ..assembly import Assembly
from ..feature import (
    AngularAcceleration,
    Feature,
    FeatureDoc,
    Output,
    OutputContext,
    OutputValue,
    Reader,
    ReadStage,
    SceneRead,
)
from ..scene_data import SceneData

# features whose torque the held rate would have to absorb: refused with it
EXCLUDED_FEATURES = ("torque_body", "torque_world", "gravity", "friction")


def check_exclusions(ctx: SceneRead) -> dict[str, Any]:
    """Refuse prescribed_rate with any of EXCLUDED_FEATURES."""
    if "prescribed_rate" in ctx.features and ctx.features & set(EXCLUDED_FEATURES):
        raise ctx.rd.fail(
            "features.prescribed_rate",
            "holds omega at its start value, so it excludes torque_body, "
            "torque_world, gravity and friction (the FMU outputs the torque that holds the rate instead)",
        )
    return {}


def bearing_torque(a: Assembly, ctx: OutputContext) -> dict[str, OutputValue]:
    """tau_bearing (N·m, world) when requested: the torque that holds the rate."""
    if "tau_bearing" not in a.scene.outputs:
        return {}
    return {
        "tau_bearing": OutputValue(
            a.rotation_matrix @ rb.inverse_dynamics_torque(a.inertia, a.omega, ctx.omega_dot),
            "N.m",
            "torque the bearings supply to hold the rate, world axis {}",
        )
    }


def _doc(scene: SceneData) -> FeatureDoc | None:
    """The held rate and the bearing torque that holds it (§4.4)."""
    if not scene.has("prescribed_rate"):
        return None
    eq = ("ω held at ω0; output τ_bearing = R (ω × I ω)", "§4.4 (MIT 2.003J)")
    return FeatureDoc("a prescribed rate (a shaft in bearings)", (eq,), replaces_euler=True)


FEATURE = Feature(
    name="prescribed_rate",
    doc=_doc,
    order=40,
    flags=("prescribed_rate",),
    readers=(Reader(ReadStage.INPUTS, 10, check_exclusions),),
    # the bearing torque that holds the rate: a torque, but it keeps ω and E
    torque_flags=frozenset({"prescribed_rate"}),
    angular_acceleration=AngularAcceleration(
        replaces=lambda scene: scene.has("prescribed_rate"), omega_dot=lambda a: ca.SX.zeros(3)
    ),
    outputs=(Output("tau_bearing", 20, frozenset({"prescribed_rate"})),),
    requested=bearing_torque,
)
