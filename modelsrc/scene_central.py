"""Scene-file rules of the central field (feature ``central_gravity``): the [central_gravity] table, exclusions.

`read_central_gravity` reads ``[central_gravity] mu`` (the central body's gravitational
parameter μ = G M, m³/s², at the world origin; Earth's by default) of a scene with
``features.central_gravity`` and refuses the combinations the model does not cover
(docs/theory.md §9.7). Called by ``modelsrc.scene.load_scene`` with its reader, so every
error names the file, the field and what is allowed.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .scene_reader import SceneReader

MU_EARTH = 3.986004418e14  # m³/s²: Earth's G M (IERS Conventions 2010, table 1.1; WGS 84)

# Features a body in the central field cannot have, and why (docs/theory.md §9.7).
EXCLUDED_FEATURES = {
    "gravity": "the uniform field g and the central field are two models of one gravity: choose one",
    "orbit": "features.orbit prescribes a circular orbit of the centre of mass; in the central field the centre "
    "of mass flies its own (Keplerian) orbit",
}
# Methods that cannot integrate the central field: the splittings' flows are those of a
# body without position-dependent torques (docs/theory.md §5.3, §7.4).
EXCLUDED_METHODS = ("splitting", "exact_free")


def read_central_gravity(rd: SceneReader, features: frozenset[str], init: dict[str, Any]) -> float:
    """μ (m³/s², finite, > 0; MU_EARTH when [central_gravity] mu is not given) when
    features.central_gravity is true, else 0.0. Refuses the feature without translation,
    with any of EXCLUDED_FEATURES, a start position at the central body, and a
    [central_gravity] table without the feature."""
    sec = rd.feature_section("central_gravity", features, EXCLUDED_FEATURES)
    if sec is None:
        return 0.0
    if "translation" not in features:
        raise rd.fail(
            "features.central_gravity",
            "needs features.translation = true (the central field pulls the centre of mass, which moves only in "
            "free flight; for a prescribed circular orbit use features.orbit)",
        )
    x0 = rd.vector("initial.x_cm", init["x_cm"], 3) if "x_cm" in init else np.zeros(3)
    if not np.any(x0 != 0.0):
        raise rd.fail(
            "initial.x_cm",
            "required and not at the origin when features.central_gravity is true: the central body sits at the "
            "world origin (m, world frame; about 7e6 in low Earth orbit)",
        )
    return rd.number("central_gravity.mu", sec.get("mu", MU_EARTH), positive=True)
