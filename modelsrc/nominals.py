"""Nominal magnitudes of a scene's state vectors: the absolute floors of error control and the FMU's nominals.

One source for three uses: the `nominal` attributes of the states in modelDescription.xml,
GetNominalsOfContinuousStates (an importer's own solver scales its error test with them),
and the absolute floors of the FMU's error-controlled stepping (docs/theory.md §5.5: a
state vector x_b is measured relative to sqrt(|x_b|² + nominal_b²), so a vector passing
through zero is held to tolerance·nominal_b, not to a vanishing relative error).

Each nominal is the size of the vector at the start with a floor from the body itself:
q is a unit quaternion (1); ω the start spin, at least W_FLOOR; a position the start
distance, at least the body's size ℓ = sqrt(tr I_cm / m) (its radius of gyration, m);
a velocity the start speed, at least ℓ·W_FLOOR. In an orbit (docs/theory.md §9.1) ω's floor
is the orbit rate n instead and the orbit angle's nominal one orbit, 2π; in a central field
(§9.7) the orbit rate √(μ/|x0|³) at the start.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import ModelInputError
from .scene import Scene

W_FLOOR = 1.0  # rad/s: slower bodies are measured against 1 rad/s, absolute


def body_size(scene: Scene) -> float:
    """ℓ = sqrt(tr I_cm / m) (m): the body's radius of gyration, its natural length scale."""
    return float(np.sqrt(np.trace(scene.inertia) / scene.mass))


def state_nominals(scene: Scene) -> dict[str, float]:
    """State vector name (q, w_body, and x_cm, v_cm or x_pivot, v_pivot, and Omega_<rotor>,
    and orbit_angle) -> its nominal magnitude in its unit (1; rad/s; m; m/s; rad/s; rad)."""
    with np.errstate(over="ignore"):  # an overflow is refused below, naming it
        return _nominals(scene)


def _nominals(scene: Scene) -> dict[str, float]:
    w_nominal = max(_magnitude(scene, "|initial.w_body|", float(np.linalg.norm(scene.w0))), W_FLOOR)
    out = {"q": 1.0, "w_body": w_nominal}
    if scene.moves:
        base = "cm" if scene.has("translation") else "pivot"
        size = _magnitude(scene, f"the body's size sqrt(tr I / m) (mass {scene.mass:g} kg)", body_size(scene))
        x = _magnitude(scene, f"|initial.x_{base}|", float(np.linalg.norm(scene.x0)))
        v = _magnitude(scene, f"|initial.v_{base}|", float(np.linalg.norm(scene.v0)))
        out[f"x_{base}"] = max(x, size)
        out[f"v_{base}"] = _magnitude(scene, f"the body's size times {W_FLOOR} rad/s", max(v, size * W_FLOOR))
    for name, r in scene.rotors.items():  # a rotor's relative rate, like ω: its start rate, at least W_FLOOR
        out[f"Omega_{name}"] = max(abs(r.Omega0), W_FLOOR)
    if scene.has("orbit"):
        # in an orbit the body turns at about n (~1e-3 rad/s in low orbit): ω is measured
        # against n, not against W_FLOOR, which would leave its error uncontrolled; the
        # orbit angle against one orbit (docs/theory.md §9.1)
        out["w_body"] = max(float(np.linalg.norm(scene.w0)), scene.orbit_rate)
        out["orbit_angle"] = 2 * math.pi
    if scene.has("central_gravity"):
        # the same for a free body in a central field (docs/theory.md §9.7): ω against the
        # orbit rate sqrt(μ/r0³) at the start distance r0 = |x0|
        n0 = math.sqrt(scene.mu / float(np.linalg.norm(scene.x0)) ** 3)
        out["w_body"] = _magnitude(
            scene, "the orbit rate sqrt(mu / |x_cm|^3)", max(float(np.linalg.norm(scene.w0)), n0)
        )
    return out


def _magnitude(scene: Scene, what: str, value: float) -> float:
    """value, or a ModelInputError when it overflowed: the nominals are written into
    modelDescription.xml and the C code, which hold finite numbers only."""
    if not math.isfinite(value):
        raise ModelInputError(
            f"scene file {scene.path}: {what} overflows double precision ({value}), so the FMU's state nominals "
            "(docs/theory.md §5.5) cannot be written: give start vectors whose components stay below 1e154 in "
            "magnitude (their squares must be finite) and a mass with tr I / m below 1e308"
        )
    return value
