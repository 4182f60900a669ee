"""Scene-file rules of the body's inertia: about the centre of mass or the pivot, and when it is diagonal.

`read_inertia` reads `[body]` principal_moments or inertia, given about the centre of mass
(default) or, for a top (`inertia_about = "pivot"`), about its pivot: the scene keeps the
tensor about the centre of mass, I_C = I_P − m(|r|² 1 − r rᵀ) (parallel-axis theorem,
docs/theory.md §3.2), checked like any inertia about the centre of mass, and the one
given about the pivot, which becomes the FMU's parameters. `diagonal_about_rotation_point`
decides which methods a scene may compile in (those that need principal axes, modelsrc.methods).
Errors name the file, the field and what is allowed (the scene reader's `fail`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import ModelInputError
from .inertia import parallel_axis_shift, validate_inertia
from .scene_reader import SceneReader

ABOUT = ("centre_of_mass", "pivot")


def given_inertia(rd: SceneReader, body: dict[str, Any]) -> tuple[np.ndarray, bool, str]:
    """(tensor as given, kg·m², body frame; principal: given as 3 principal moments; the
    point it is about: "centre_of_mass" or "pivot"). Not validated yet (`read_inertia`)."""
    if ("principal_moments" in body) == ("inertia" in body):
        raise rd.fail("body", "give exactly one of 'principal_moments' (3 numbers) or 'inertia' (3x3 rows)")
    about = body.get("inertia_about", "centre_of_mass")
    if about not in ABOUT:
        raise rd.fail("body.inertia_about", f"must be one of {', '.join(repr(a) for a in ABOUT)}, got {about!r}")
    if "principal_moments" in body:
        return np.diag(rd.vector("body.principal_moments", body["principal_moments"], 3)), True, about
    rows = body["inertia"]
    if not isinstance(rows, list) or len(rows) != 3:
        raise rd.fail("body.inertia", f"must be 3 rows of 3 numbers, got {rows!r}")
    return np.array([rd.vector(f"body.inertia[{i + 1}]", r, 3) for i, r in enumerate(rows)]), False, about


def read_inertia(
    rd: SceneReader, body: dict[str, Any], features: frozenset[str], mass: float, r_cm: np.ndarray | None
) -> tuple[np.ndarray, bool, np.ndarray | None]:
    """(inertia about the centre of mass, principal, inertia about the pivot as given or
    None), validated. A tensor about the pivot needs a pivot (features.gravity without
    translation); the tensor about the centre of mass it implies must be a valid inertia."""
    raw, principal, about = given_inertia(rd, body)
    field = "body." + ("principal_moments" if principal else "inertia")
    if about == "centre_of_mass":
        try:
            return validate_inertia(raw, what="body inertia about the centre of mass"), principal, None
        except ModelInputError as exc:
            raise rd.fail(field, str(exc)) from None
    if r_cm is None or "translation" in features:
        raise rd.fail(
            "body.inertia_about",
            "'pivot' needs a pivot: features.gravity with [gravity] r_cm, and no translation (a free body turns "
            "about its centre of mass)",
        )
    raw = 0.5 * (raw + raw.T) if not principal else raw
    try:
        validate_inertia(raw, what="body inertia about the pivot")
        cm = validate_inertia(
            raw - parallel_axis_shift(np.zeros((3, 3)), mass, r_cm),
            what=f"inertia about the centre of mass implied by it (I_pivot - m(|r|^2 1 - r r^T), m = {mass:g} kg, "
            f"r_cm = {list(map(float, r_cm))} m)",
        )
    except ModelInputError as exc:
        raise rd.fail(field, str(exc)) from None
    return cm, principal, raw


def diagonal_about_rotation_point(
    inertia_cm: np.ndarray, pivot_inertia: np.ndarray | None, features: frozenset[str], r_cm: np.ndarray | None
) -> bool:
    """True when the inertia about the point the body turns about is diagonal in body
    axes (exactly, as given: a full tensor with zero products of inertia counts as well
    as principal moments): the methods with `needs_principal` (modelsrc.methods) may be
    compiled in only then. A prescribed rate has none of them."""
    if "prescribed_rate" in features:
        return False
    off = ~np.eye(3, dtype=bool)
    if pivot_inertia is not None:
        return not np.any(pivot_inertia[off])
    if "gravity" in features and "translation" not in features and r_cm is not None:
        # the shift to the pivot adds the products of inertia -m r_i r_j: zero when r_cm lies on an axis
        return not np.any(inertia_cm[off]) and int(np.count_nonzero(r_cm)) <= 1
    return not np.any(inertia_cm[off])
