"""Nominal magnitudes of a scene's state vectors: the absolute floors of error control and the FMU's nominals.

One source for three uses: the `nominal` attributes of the states in modelDescription.xml,
GetNominalsOfContinuousStates (an importer's own solver scales its error test with them),
and the absolute floors of the FMU's error-controlled stepping (docs/theory.md §5.5: a
state vector x_b is measured relative to sqrt(|x_b|² + nominal_b²), so a vector passing
through zero is held to tolerance·nominal_b, not to a vanishing relative error).

Each nominal is the size of the vector at the start with a floor from the body itself:
q is a unit quaternion (1); ω the start spin, at least W_FLOOR; the features add theirs
(modelsrc.feature, `nominals`): a position the start distance, at least the body's size
ℓ = sqrt(tr I_cm / m) (its radius of gyration, m); a velocity the start speed, at least
ℓ·W_FLOOR; a rotor's rate like ω. In an orbit (docs/theory.md §9.1) ω's floor is the
orbit rate n instead and the orbit angle's nominal one orbit, 2π; in a central field
(§9.7) the orbit rate √(μ/|x0|³) at the start.
"""

from __future__ import annotations

import numpy as np

from .nominal_floors import W_FLOOR, body_size, checked_magnitude
from .registry import FEATURE_UNITS
from .scene_data import SceneData

__all__ = ["W_FLOOR", "body_size", "state_nominals"]


def state_nominals(scene: SceneData) -> dict[str, float]:
    """State vector name (q, w_body, and x_cm, v_cm or x_pivot, v_pivot, and Omega_<rotor>,
    and orbit_angle) -> its nominal magnitude in its unit (1; rad/s; m; m/s; rad/s; rad)."""
    with np.errstate(over="ignore"):  # an overflow is refused, naming it
        w_nominal = max(checked_magnitude(scene, "|initial.w_body|", float(np.linalg.norm(scene.w0))), W_FLOOR)
        out = {"q": 1.0, "w_body": w_nominal}
        for feature in FEATURE_UNITS:
            if feature.nominals is not None:
                feature.nominals(scene, out)
    return out
