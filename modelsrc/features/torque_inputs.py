"""Torque inputs as one feature (``torque_body``, ``torque_world``): the inputs tau_body, tau_world and their torque.

An importer drives the body with a torque given in the body frame, tau_body (N·m), or in
the world frame, tau_world (N·m), turned into the body frame by Rᵀ (docs/theory.md §4).
`FEATURE` declares them (modelsrc.feature).
"""

from __future__ import annotations

import casadi as ca

from .. import rigid_body as rb
from ..assembly import Assembly
from ..feature import Builder, Feature, FeatureDoc, Phase
from ..scene_data import SceneData
from ..variables import Kind, vector_names

# flag -> the input it makes
INPUTS = {"torque_body": "tau_body", "torque_world": "tau_world"}


def add_torque_inputs(a: Assembly) -> None:
    """Inputs tau_body (N·m, body) and tau_world (N·m, world, turned into the body by Rᵀ)."""
    for feature, name, frame, to_body in (
        ("torque_body", "tau_body", "body", lambda t: t),
        ("torque_world", "tau_world", "world", lambda t: rb.world_to_body_torque(a.rotation, t)),
    ):
        if not a.scene.has(feature):
            continue
        sym = ca.SX.sym(name, 3)
        a.input_blocks.append(sym)
        a.torque = a.torque + to_body(sym)
        a.add(
            vector_names(name, 3),
            Kind.INPUT,
            list(a.scene.input_start(name)),
            "N.m",
            [f"applied torque, {frame} axis {i}" for i in (1, 2, 3)],
        )


def torque_input_names(scene: SceneData) -> list[str]:
    """tau_body and tau_world, those the scene has, in value-reference order."""
    return [name for flag, name in INPUTS.items() if scene.has(flag)]


def _doc(scene: SceneData) -> FeatureDoc | None:
    """The torque inputs the scene has, and their terms of τ (docs/theory.md §2.2)."""
    eqs = {"torque_body": ("τ += τ_body  (input, body frame)", "§2.2"),
           "torque_world": ("τ += R(q)ᵀ τ_world  (input, world frame)", "§2.2")}  # fmt: skip
    used = [f for f in eqs if scene.has(f)]
    return FeatureDoc(f"torque inputs {', '.join(used)}", tuple(eqs[f] for f in used)) if used else None


FEATURE = Feature(
    name="torque_inputs",
    doc=_doc,
    order=10,
    flags=tuple(INPUTS),
    input_of_flag=INPUTS,
    torque_flags=frozenset(INPUTS),
    working_flags=frozenset(INPUTS),
    input_names=torque_input_names,
    builders=(Builder(Phase.INPUTS, 10, add_torque_inputs),),
)
