"""Which closed form of rbcheck gives a scene's rotation, and that rotation: one dispatcher for checks and report.

A scene's body rate ω(t) and attitude q(t) have a closed form here when (docs/theory.md §2.3,
§4.2, §4.4):

- the rate is held (prescribed_rate): the uniform rotation (rbcheck.closed_forms.uniform_rotation);
- no torque acts and the inertia is diagonal in body axes: the free symmetric body
  (I1 = I2, rbcheck.closed_forms.free_symmetric) or the free asymmetric one (three distinct
  moments, Jacobi's elliptic functions, rbcheck.closed_forms.free_asymmetric);
- gravity is the only torque and nothing dissipates: the Lagrange top (diag(I1, I1, I3),
  r_cm = l e3, g = −g e_z; rbcheck.closed_forms.heavy_top, I1 taken about the pivot).

A body with rotors (a gyrostat) has none. The centre of mass of a body in free flight is not
this module's: rbcheck.closed_forms.free_flight gives its parabola where only uniform gravity
acts on it. A scene is read as data (any object with the fields of modelsrc.scene.Scene:
rbcheck's references import no modelsrc, docs/architecture.md). Units SI; ω (rad/s) in the
body frame, q body -> world (scalar first).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from . import free_asymmetric, free_symmetric, uniform_rotation
from . import heavy_top as ht


class NoClosedForm(ValueError):
    """No closed form of rbcheck gives the scene's rotation; the message says why."""


class ClosedRotation(NamedTuple):
    """w (n, 3) rad/s body and q (n, 4) body -> world at the times asked, and the closed
    form's name ("rbcheck.closed_forms.<module>", a note in brackets where it helps)."""

    w: NDArray[np.float64]
    q: NDArray[np.float64]
    name: str


def is_principal_diag(I: NDArray) -> bool:
    """True when the 3x3 inertia [kg m^2] is diagonal in body axes (exactly)."""
    return bool(np.all(np.asarray(I)[~np.eye(3, dtype=bool)] == 0.0))


def top_params(scene: Any) -> ht.TopParams:
    """Lagrange-top parameters of a gravity scene. I1 is the transverse moment about the
    PIVOT, ``I1 = I1_cm + M l^2`` (parallel-axis theorem, docs/theory.md §3.2), since the
    closed form (Korean notes ⊕) is written about the fixed point.

    Requires a symmetric top: diagonal inertia with I11 = I22, r_cm = l e3 (l > 0) and
    g = -g e_z; raises ValueError naming the offending value otherwise."""
    I = np.asarray(scene.inertia, dtype=float)
    r = np.asarray(scene.r_cm, dtype=float)
    g = np.asarray(scene.g, dtype=float)
    if not is_principal_diag(I) or I[0, 0] != I[1, 1]:
        raise ValueError(
            f"scene {scene.name}: the heavy-top closed form needs diag(I1, I1, I3), got inertia {I.tolist()}"
        )
    if r[0] != 0.0 or r[1] != 0.0 or not r[2] > 0.0:
        raise ValueError(f"scene {scene.name}: r_cm must be (0, 0, l) with l > 0, got {r.tolist()}")
    if g[0] != 0.0 or g[1] != 0.0 or not g[2] < 0.0:
        raise ValueError(f"scene {scene.name}: g must be (0, 0, -g) with g > 0, got {g.tolist()}")
    M, l = float(scene.mass), float(r[2])
    return ht.TopParams(I1=float(I[0, 0]) + M * l * l, I3=float(I[2, 2]), M=M, g=float(-g[2]), l=l)


def closed_rotation(scene: Any, t: NDArray) -> ClosedRotation:
    """The closed-form rotation of the scene at times t (s); NoClosedForm, with the reason,
    where none of rbcheck covers it (see the module's docstring)."""
    if scene.rotors:
        raise NoClosedForm(
            "there is no closed-form trajectory of a body with rotors (a gyrostat) in rbcheck; the rotors' own "
            "checks compare it with Exudyn and scipy"
        )
    if scene.has("prescribed_rate"):  # ω̇ = 0 in place of Euler's equations (docs/theory.md §4.4)
        w, q = uniform_rotation.solve(scene.w0, scene.q0, t)
        return ClosedRotation(w, q, "rbcheck.closed_forms.uniform_rotation (a held rate)")
    I = np.asarray(scene.inertia, dtype=float)
    if scene.torque_free:
        if not is_principal_diag(I):
            raise NoClosedForm("torque-free, but the inertia is not diagonal in body axes (the closed forms need it)")
        d = np.diag(I)
        if d[0] == d[1]:
            w, q = free_symmetric.solve(d[0], d[2], scene.w0, scene.q0, t)
            return ClosedRotation(w, q, "rbcheck.closed_forms.free_symmetric")
        try:
            w, q = free_asymmetric.solve(d, scene.w0, scene.q0, t)
        except ValueError as exc:  # e.g. I2 == I3: symmetric about another body axis
            raise NoClosedForm(f"rbcheck.closed_forms.free_asymmetric: {exc} (free_symmetric needs I1 == I2)") from None
        return ClosedRotation(w, q, "rbcheck.closed_forms.free_asymmetric")
    if scene.has("gravity") and scene.conserves_energy:
        try:
            top = ht.HeavyTop(top_params(scene), ht.init_from_state(scene.q0, scene.w0))
        except ValueError as exc:
            raise NoClosedForm(f"not a Lagrange top that rbcheck.closed_forms.heavy_top covers: {exc}") from None
        return ClosedRotation(top.omega(t), top.quaternion(t), "rbcheck.closed_forms.heavy_top")
    sources = sorted(scene.features - {"translation"}) + [
        f"force point {n}" for n, fp in scene.force_points.items() if np.any(fp.point != 0.0)
    ]
    raise NoClosedForm(
        f"torques act ({', '.join(sources)}) and the scene is not a frictionless Lagrange top: rbcheck has no "
        "closed form"
    )


def parabola_applies(scene: Any) -> bool:
    """The centre of mass of a body in free flight follows rbcheck.closed_forms.free_flight's
    parabola: no force acts on it but uniform gravity (no force inputs or points, no central
    field)."""
    forces = scene.features & {"force_body", "force_world", "central_gravity"}
    return not forces and not scene.force_points
