"""``rbfmu check``: FMU vs Exudyn vs closed forms, as a registry of small checks.

Modules: ``registry`` (registration, report types, ``scene_report``, tables),
``common`` (scene/FMU/Exudyn plumbing), ``free_body`` (tennis racket, symmetric-top
rates), ``tops`` (heavy-top nutation, fast top), ``sleeping_top`` (threshold, growth,
friction onset), ``trajectories`` (FMU vs Exudyn, conserved drifts), ``generic`` (the
checks every scene gets), ``scenes`` (one specific check per shipped scene), ``motion``
and ``balances`` (the scenes whose reference point moves, and their work and momentum
balances), ``orbit`` (the gravity-gradient boom: librations, Jacobi integral, scipy and
Exudyn), ``momentum_bias`` (a wheel along the orbit normal: roll–yaw and pitch frequencies),
``central`` (the eccentric orbit: invariants, Kepler, scipy), ``feature_table``
(which checks each feature gets: ``feature_checks`` for the rotors and the scipy reference,
``orbit_features`` for the orbit and the central field), ``cli`` (entry point).
Importing the package registers every check.
"""

from . import central, feature_table, generic, momentum_bias, motion, orbit, propellers, scenes, wheels  # noqa: F401
from .registry import (
    CheckOutput,
    GenericOutcome,
    NotApplicable,
    Row,
    SceneReport,
    format_report,
    generic_check,
    generic_checks,
    registered_scenes,
    scene_check,
    scene_report,
)

__all__ = [
    "CheckOutput",
    "GenericOutcome",
    "NotApplicable",
    "Row",
    "SceneReport",
    "format_report",
    "generic_check",
    "generic_checks",
    "registered_scenes",
    "scene_check",
    "scene_report",
]
