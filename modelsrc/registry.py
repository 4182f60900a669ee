"""The registered features: every unit of modelsrc/features/ in order, and the tables and sums that loop over them.

A unit is a module ``modelsrc/features/<name>.py`` or a folder ``modelsrc/features/<name>/``
whose ``feature.py`` defines ``FEATURE`` (a ``modelsrc.feature.Feature``); this module
finds them all, so adding a capability is adding its unit (docs/features.md). Everything
that depends on the features a scene uses reads them from here: the scene reader's
tables and readers (modelsrc.scene), the scene's properties, the model's builders in
value-reference order and the features' contributions (modelsrc.model,
modelsrc.model_functions) and the states' nominals (modelsrc.nominals).
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Mapping
from typing import Any

from . import features as features_package
from .feature import AngularAcceleration, Builder, Feature, FeatureDoc, Output, Phase, Reader, ReadStage
from .scene_data import SceneData


def discover() -> tuple[Feature, ...]:
    """The FEATURE of every unit of modelsrc/features/, in their `order`; refuses a unit
    without one and two units that claim the same order, name, flag, table or rank."""
    found = []
    for info in pkgutil.iter_modules(features_package.__path__):
        module_name = f"{features_package.__name__}.{info.name}" + (".feature" if info.ispkg else "")
        feature = getattr(importlib.import_module(module_name), "FEATURE", None)
        if not isinstance(feature, Feature):
            raise TypeError(f"{module_name} defines no FEATURE (a modelsrc.feature.Feature): every unit must")
        found.append(feature)
    units = tuple(sorted(found, key=lambda f: f.order))
    _check_unique("order", [f.order for f in units])
    _check_unique("name", [f.name for f in units])
    _check_unique("flag", [flag for f in units for flag in f.flags])
    _check_unique("table", [t for f in units for t in f.tables])
    _check_unique("builder rank", [(b.phase, b.rank) for f in units for b in f.builders])
    _check_unique("reader rank", [(r.stage, r.rank) for f in units for r in f.readers])
    return units


def _check_unique(what: str, values: list[Any]) -> None:
    repeated = sorted({repr(v) for v in values if values.count(v) > 1})
    if repeated:
        raise ValueError(f"two features claim the same {what}: {', '.join(repeated)}")


FEATURE_UNITS: tuple[Feature, ...] = discover()

# The flags of [features] (scene.FEATURES), in the features' order.
FLAGS: tuple[str, ...] = tuple(flag for f in FEATURE_UNITS for flag in f.flags)
# Flags that put a torque on the body about the point it turns about (the features'
# `adds_torque` refine them: gravity on a free body acts at the centre of mass).
TORQUE_FLAGS = frozenset(flag for f in FEATURE_UNITS for flag in f.torque_flags)
# Flags whose torques or forces do work that is not the change of a potential.
WORKING_FLAGS = frozenset(flag for f in FEATURE_UNITS for flag in f.working_flags)
# Flags that move the reference point (centre of mass or pivot).
MOTION_FLAGS = frozenset(flag for f in FEATURE_UNITS for flag in f.motion_flags)
# flag -> the input it makes (tau_body, f_world, a_pivot ...)
INPUT_OF_FLAG: dict[str, str] = {flag: name for f in FEATURE_UNITS for flag, name in f.input_of_flag.items()}
# table of a scene file -> the keys it allows, for the features' tables read by key
TABLE_KEYS: dict[str, frozenset[str]] = {
    table: keys for f in FEATURE_UNITS for table, keys in f.tables.items() if keys is not None
}
# every top-level table a feature owns
TABLES: tuple[str, ...] = tuple(table for f in FEATURE_UNITS for table in f.tables)
# flags that need body.mass, in the features' order
NEEDS_MASS: tuple[str, ...] = tuple(flag for f in FEATURE_UNITS for flag in f.needs_mass)
# The outputs a scene may request beyond the body's, in their ranks' order.
OUTPUT_DECLARATIONS: tuple[Output, ...] = tuple(
    sorted((o for f in FEATURE_UNITS for o in f.outputs), key=lambda o: o.rank)
)


def builders(phase: Phase) -> tuple[Builder, ...]:
    """The features' builders of one value-reference phase, in their ranks' order."""
    return tuple(sorted((b for f in FEATURE_UNITS for b in f.builders if b.phase == phase), key=lambda b: b.rank))


def readers(stage: ReadStage) -> tuple[Reader, ...]:
    """The features' readers of one stage of load_scene, in their ranks' order."""
    return tuple(sorted((r for f in FEATURE_UNITS for r in f.readers if r.stage == stage), key=lambda r: r.rank))


def start_keys(data: Mapping[str, Any]) -> frozenset[str]:
    """The [initial] keys the features allow in the parsed scene file `data`."""
    return frozenset(k for f in FEATURE_UNITS for k in f.start_keys(data))


def file_inputs(fields: Mapping[str, Any]) -> frozenset[str]:
    """The [inputs] keys the scene's fields allow: each flag's input and the features' own."""
    return frozenset(INPUT_OF_FLAG.values()) | frozenset(k for f in FEATURE_UNITS for k in f.file_inputs(fields))


def derived_inputs(inputs: dict[str, Any], fields: Mapping[str, Any]) -> dict[str, Any]:
    """The input schedules with those the features derive from the given ones, for a scene
    of the given fields."""
    for f in FEATURE_UNITS:
        if f.derived_inputs is not None:
            inputs = f.derived_inputs(inputs, fields)
    return inputs


def derived_input_names(fields: Mapping[str, Any]) -> frozenset[str]:
    """The inputs the features always derive from others (a speed-mode rotor's Omega_dot_<name>
    from its Omega_<name>): a run's driver overrides any value given for them."""
    return frozenset(n for f in FEATURE_UNITS for n in f.derived_input_names(fields))


def refused_methods(features: frozenset[str], fields: Mapping[str, Any]) -> list[tuple[tuple[str, ...], str]]:
    """(methods, why) of every feature of the scene that refuses methods, in order."""
    return [(f.excluded_methods, f.excluded_why) for f in FEATURE_UNITS if f.excludes_methods(features, fields)]


def torque_free(scene: SceneData) -> bool:
    """No feature puts a torque on the body about the point it turns about."""
    return not any(f.torque_on(scene) for f in FEATURE_UNITS)


def conserves_energy(scene: SceneData) -> bool:
    """No feature's forces or torques do work that is not the change of a potential."""
    return not any(f.works_on(scene) for f in FEATURE_UNITS)


def keeps_exact_flow(scene: SceneData) -> bool:
    """No feature leaves the exact flow of the rigid body (states or frames of its own,
    forces turning with the body)."""
    return not any(f.blocks_exact_flow(scene) for f in FEATURE_UNITS)


def input_names(scene: SceneData) -> list[str]:
    """The scene's FMU inputs in value-reference order (the features' inputs phase)."""
    ranked = [(b.rank, f) for f in FEATURE_UNITS for b in f.builders if b.phase == Phase.INPUTS]
    return [name for _, f in sorted(ranked, key=lambda rf: rf[0]) for name in f.input_names(scene)]


def angular_acceleration(scene: SceneData) -> AngularAcceleration | None:
    """The feature's ω̇ that replaces Euler's equations in the scene, or None (Euler's)."""
    found = [f.angular_acceleration for f in FEATURE_UNITS if f.angular_acceleration is not None]
    active = [aa for aa in found if aa.replaces(scene)]
    return active[0] if active else None


def feature_docs(scene: SceneData) -> list[tuple[str, FeatureDoc]]:
    """(feature name, its FeatureDoc) of every feature the scene uses, in order: what the
    FMU's documentation says of its features and equations (fmu.build.archive_docs)."""
    return [(f.name, d) for f in FEATURE_UNITS if (d := f.doc(scene)) is not None]


def conserved_quantities(scene: SceneData) -> list[str]:
    """What the scene's physics conserves (with its output and docs/theory.md section): the
    energy where no feature works on the body, the world angular momentum where none puts a
    torque on it (§2.3), and each feature's own (`FeatureDoc.conserved`: the Jacobi integral
    of an orbit, §9.3) where no other feature works on the body."""
    out = []
    if conserves_energy(scene):
        out.append("the energy E_total (E_kin without a potential): no force or torque works on the body (§2.3)")
    if torque_free(scene):
        out.append("the angular momentum L_world: no torque on the body about the point it turns about (§2.3)")
    for f in FEATURE_UNITS:
        d = f.doc(scene)
        if d is not None and not any(g.works_on(scene) for g in FEATURE_UNITS if g is not f):
            out.extend(d.conserved)
    return out
