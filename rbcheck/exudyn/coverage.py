"""Which scenes the rigid-body Exudyn models cover, without loading Exudyn: a reference that models the physics or none.

`covers` is asked before a run by rbcheck.exudyn.motion.simulate (which refuses the
others), by the checks (rbcheck.checks.trajectories) and by the report's batch part
(rbcheck.workprecision.batch), so that no caller compares with a body that lacks a
scene's torque or force.
"""

from __future__ import annotations

from typing import Any

# Scene features the models of rbcheck.exudyn.motion.simulate reproduce (rbcheck.exudyn.models, "Models" and
# "Friction" in its docstring: free body, spherical pivot with the weight, rotational
# damper, body- and world-frame torque loads; rbcheck.exudyn.motion: six-degree-of-freedom body with
# force loads at markers, spherical joint to a prescribed shaker). A prescribed rate, an
# orbit's gravity gradient and a central field are not among them: Exudyn would simulate
# a free body in their place.
EXUDYN_FEATURES = frozenset(
    {"torque_body", "torque_world", "gravity", "friction", "translation", "force_body", "force_world", "moving_pivot"}
)


def covers(scene: Any) -> str | None:
    """None when rbcheck.exudyn.motion.simulate models the scene, else why not: rotors (their model is
    rbcheck.exudyn.rotors), an orbit (rbcheck.exudyn.orbit), or a feature outside
    EXUDYN_FEATURES, which the models would leave out and so simulate another system."""
    if getattr(scene, "rotors", None):
        return "the scene has rotors: their Exudyn model is rbcheck.exudyn.rotors (the rigid-body models have none)"
    if "orbit" in getattr(scene, "features", ()):
        return (
            "the scene is in an orbit: Exudyn's orbit model is rbcheck.exudyn.orbit (the rigid-body models have none)"
        )
    missing = sorted(set(getattr(scene, "features", ())) - EXUDYN_FEATURES)
    if missing:
        return f"the Exudyn models (rbcheck.exudyn.models, rbcheck.exudyn.motion) have no {', '.join(missing)}"
    return None
