"""Scene-file rules of the circular orbit (features ``orbit``, ``gravity_gradient``): the [orbit] table, exclusions.

`read_orbit` reads ``[orbit] rate`` (the orbit rate n, rad/s) of a scene with
``features.orbit`` and refuses the feature combinations the orbit model does not cover
(docs/theory.md §9). Called by ``modelsrc.scene.load_scene`` with its reader, so every
error names the file, the field and what is allowed.
"""

from __future__ import annotations

from .scene_reader import SceneReader

# Features an orbiting body cannot have, and why. The orbit is a prescribed circular motion
# of the centre of mass (docs/theory.md §9.1): a free centre of mass (translation) flies
# its own orbit in features.central_gravity (§9.7), a pivot (gravity: the heavy top's uniform
# field, moving_pivot) has no meaning in free fall, and a prescribed rate holds ω, which
# the gravity-gradient torque would have to be absorbed against.
EXCLUDED_FEATURES = {
    "translation": "the centre of mass follows the prescribed circular orbit; for a free centre of mass in a "
    "central field (a Keplerian orbit) use features.central_gravity instead of features.orbit",
    "moving_pivot": "an orbiting body turns about its centre of mass, it has no pivot",
    "gravity": "the uniform field of a heavy top about a pivot has no meaning in free fall; the orbit's "
    "gravity acts through features.gravity_gradient",
    "prescribed_rate": "it holds omega at its start value against the orbit's torques (tau_bearing does not "
    "include them)",
}
# Methods that cannot integrate the orbit angle: the splittings' flows are those of (q, ω)
# of a rigid body in an inertial frame (docs/theory.md §5.3).
EXCLUDED_METHODS = ("splitting", "exact_free")


def read_orbit(rd: SceneReader, features: frozenset[str]) -> float:
    """The orbit rate n (rad/s, finite and > 0) of [orbit] rate when features.orbit is
    true, else 0.0; refuses gravity_gradient without orbit, an [orbit] table without the
    feature, and orbit with any of EXCLUDED_FEATURES."""
    if "gravity_gradient" in features and "orbit" not in features:
        raise rd.fail(
            "features.gravity_gradient",
            "needs features.orbit = true (the torque 3 n^2 c x (I c) needs the orbit rate n and the nadir c)",
        )
    sec = rd.feature_section("orbit", features, EXCLUDED_FEATURES)
    if sec is None:
        return 0.0
    if "rate" not in sec:
        raise rd.fail(
            "orbit.rate",
            "required when features.orbit is true: the orbit rate n = 2 pi / period (rad/s, finite, > 0; "
            "about 1.1e-3 in low Earth orbit)",
        )
    return rd.number("orbit.rate", sec["rate"], positive=True)
