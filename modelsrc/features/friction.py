"""Viscous friction as one feature (``friction``): the [friction] table, the coefficient c and the torque −c ω.

The torque −c ω (docs/theory.md §4.3) is dissipative: the splittings damp it exactly
instead of kicking with it (`Assembly.add_dissipative_torque`), and the equations on
principal axes take it as the rates c/I_i (the coefficient is the body's shared
`friction_coefficient`). `FEATURE` declares it (modelsrc.feature).
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from .. import rigid_body as rb
from ..assembly import Assembly
from ..feature import Builder, Feature, FeatureDoc, Phase, Reader, ReadStage, SceneRead
from ..scene_data import SceneData


def read_friction(ctx: SceneRead) -> dict[str, Any]:
    """[friction] c (N·m·s/rad, >= 0), required with features.friction and refused without."""
    rd = ctx.rd
    fric = rd.section("friction")
    if "friction" in ctx.features:
        if "c" not in fric:
            raise rd.fail("friction.c", "required when features.friction is true (N*m*s/rad, >= 0)")
        return {"c_friction": rd.number("friction.c", fric["c"], nonneg=True)}
    if fric:
        raise rd.fail("friction", "given but features.friction is not true")
    return {}


def add_friction(a: Assembly) -> None:
    """Viscous friction −c ω (docs/theory.md §4.3); not part of the splittings' kick,
    which damp it exactly."""
    if not a.scene.has("friction"):
        return
    c = a.friction_coefficient = ca.SX.sym("c_friction")
    a.friction_index = a.parameter(
        c, ["c_friction"], [a.scene.c_friction], "N.m.s/rad", ["viscous friction coefficient: torque -c*w_body"]
    )
    a.checks.append(("c_friction must be >= 0", c, False))
    a.add_dissipative_torque(rb.friction_torque(a.omega, c))


def _doc(scene: SceneData) -> FeatureDoc | None:
    """Viscous friction's torque (§4.3)."""
    return FeatureDoc("viscous friction", (("τ += −c ω", "§4.3"),)) if scene.has("friction") else None


FEATURE = Feature(
    name="friction",
    doc=_doc,
    order=30,
    flags=("friction",),
    tables={"friction": frozenset({"c"})},
    readers=(Reader(ReadStage.INERTIA, 10, read_friction),),
    torque_flags=frozenset({"friction"}),
    working_flags=frozenset({"friction"}),
    builders=(Builder(Phase.PARAMETERS, 50, add_friction),),
)
