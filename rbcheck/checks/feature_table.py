"""Which independent checks each feature of a scene gets: one table, one entry per feature unit of modelsrc/features/.

``rbfmu check --scene FILE`` runs, besides the generic checks every scene gets
(rbcheck.checks.generic: closed-form trajectory, FMU vs Exudyn, conserved-quantity drift,
input balances), the checks listed here for every feature the scene uses (when no check is
registered for the scene itself, as for the shipped ones). A new feature adds its entry
here: the generic checks that cover it and its own, with a predicate saying when a scene
uses it. tests/checks/test_feature_checks.py fails for a feature unit without an entry.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from modelsrc.scene import Scene

from .feature_checks import rotor_exudyn_check, rotor_momentum_check, scipy_reference_check
from .orbit_features import (
    central_invariants_check,
    jacobi_check,
    orbit_exudyn_check,
    pitch_libration_check,
    runge_lenz_check,
)
from .registry import GenericCheck, feature_table, generic_checks

__all__ = ["FEATURE_CHECKS", "FeatureChecks", "check_outputs", "checks_for", "features_used"]


@dataclass(frozen=True)
class FeatureChecks:
    """One feature unit's checks: `unit` (its name in modelsrc/features/), `uses(scene)`,
    `generic` (titles of the generic checks that cover it), `checks` (title, check) of its own,
    and `outputs` its checks read (added to the FMU that ``rbfmu check`` builds)."""

    unit: str
    uses: Callable[[Any], bool]
    generic: tuple[str, ...] = ()
    checks: tuple[tuple[str, GenericCheck], ...] = ()
    outputs: tuple[str, ...] = ()


_DRIFT, _BALANCES = "conserved-quantity drift", "input balances"
_CLOSED, _EXUDYN = "closed-form trajectory", "FMU vs Exudyn trajectories"
SCIPY = ("scipy reference (rbcheck.baselines)", scipy_reference_check)

FEATURE_CHECKS: tuple[FeatureChecks, ...] = (
    FeatureChecks("torque_inputs", lambda s: bool(s.features & {"torque_body", "torque_world"}),
                  (_CLOSED, _EXUDYN, _DRIFT, _BALANCES)),
    FeatureChecks("gravity", lambda s: s.has("gravity"), (_CLOSED, _EXUDYN, _DRIFT, _BALANCES)),
    FeatureChecks("friction", lambda s: s.has("friction"), (_EXUDYN, _DRIFT, _BALANCES)),
    FeatureChecks("prescribed_rate", lambda s: s.has("prescribed_rate"), (_BALANCES,)),
    FeatureChecks("free_motion", lambda s: bool(s.features & {"translation", "force_body", "force_world",
                                                               "moving_pivot"}) or bool(s.force_points),
                  (_CLOSED, _EXUDYN, _DRIFT, _BALANCES)),
    FeatureChecks(
        "rotors", lambda s: bool(s.rotors), (_DRIFT, _BALANCES),
        (("rotors: total angular momentum", rotor_momentum_check),
         ("rotors: Exudyn jointed gyrostat", rotor_exudyn_check),
         SCIPY),
        ("q", "w_body", "w_world", "E_kin", "L_world"),
    ),
    FeatureChecks(
        "orbit", lambda s: s.has("orbit"), (_DRIFT,),
        (("orbit: Jacobi integral", jacobi_check),
         ("orbit: Exudyn orbit model", orbit_exudyn_check),
         ("orbit: pitch libration closed form", pitch_libration_check),
         SCIPY),
        ("q", "w_body", "E_kin"),
    ),
    FeatureChecks(
        "central_gravity", lambda s: s.has("central_gravity"), (_DRIFT,),
        (("central field: E_total and L_total", central_invariants_check),
         ("central field: Runge-Lenz vector", runge_lenz_check),
         SCIPY),
        ("q", "w_body", "E_kin", "E_total", "x_cm", "v_cm"),
    ),
    FeatureChecks("sensor", lambda s: s.sensor_point is not None, ()),
)  # fmt: skip


def features_used(scene: Scene) -> list[FeatureChecks]:
    """The entries of the features the scene uses, in the table's order."""
    return [f for f in FEATURE_CHECKS if f.uses(scene)]


@feature_table
def checks_for(scene: Scene) -> list[tuple[str, GenericCheck]]:
    """The own checks of every feature the scene uses, each once, in the table's order."""
    out: dict[str, GenericCheck] = {}
    for f in features_used(scene):
        for title, check in f.checks:
            out.setdefault(title, check)
    return list(out.items())


def check_outputs(scene: Scene) -> tuple[str, ...]:
    """The outputs the feature checks of the scene read that it does not request (in order)."""
    from modelsrc.scene import OUTPUT_NEEDS, OUTPUTS

    want = [o for f in features_used(scene) for o in f.outputs]
    ok = [
        o for o in dict.fromkeys(want) if o in OUTPUTS and (o not in OUTPUT_NEEDS or scene.features & OUTPUT_NEEDS[o])
    ]
    return tuple(o for o in ok if o not in scene.outputs)


def unknown_generic_titles() -> list[str]:
    """Generic titles named in the table that no generic check is registered under (for the tests)."""
    known = set(generic_checks())
    return sorted({t for f in FEATURE_CHECKS for t in f.generic} - known)
