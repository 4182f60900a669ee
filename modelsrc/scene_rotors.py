"""Scene-file rules of the rotors (feature ``rotors``, the gyrostat): [rotors.<name>] tables and their start rates.

`read_rotors` reads each ``[rotors.<name>]`` (a spin axis in the body frame and an axial
inertia) and its start rate ``initial.Omega_<name>``, and refuses inertias that leave the
rest of the body without a positive definite inertia (docs/theory.md §8.1). Called by
``modelsrc.scene.load_scene`` with its reader, so every error names the file, the field
and what is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .scene_limits import MAX_ROTORS, check_scene_limits
from .scene_reader import SceneReader

# An axis this close to unit length is normalised; farther off it is refused, so that a
# typo (an axis of length 2, or 0) is not silently turned into another direction.
AXIS_NORM_TOL = 1e-9
# Features a body with rotors cannot have: a prescribed rate holds ω, but the rotor
# reaction −Σ g u is a torque on the body the bearing torque would have to absorb; the
# output tau_bearing does not include it (a later increment of issue 28).
EXCLUDED_FEATURES = ("prescribed_rate",)
# Methods that cannot integrate the rotor states: the splittings work on (q, ω) only (their
# free flows are those of the rigid body, not of the gyrostat, docs/theory.md §5.3).
EXCLUDED_METHODS = ("splitting", "exact_free")
# Rotor names whose variables would repeat others': h_<name> the step report's h_max, h_last,
# h_next; a name abs_<x> makes Omega_abs_<x>, the absolute-rate output of a rotor <x>.
RESERVED_NAMES = frozenset({"max", "last", "next"})


@dataclass(frozen=True)
class Rotor:
    """A rotor of the gyrostat: axis g (unit vector, body frame), axial inertia J (kg·m², about
    its axis) and start rate Omega0 (rad/s, relative to the body, positive right-handed about g)."""

    axis: np.ndarray
    J: float
    Omega0: float


def rotor_start_keys(data: dict[str, Any]) -> frozenset[str]:
    """The [initial] keys the scene's rotors allow: Omega_<name> for every [rotors.<name>]."""
    sec = data.get("rotors", {})
    return frozenset(f"Omega_{n}" for n in sec) if isinstance(sec, dict) else frozenset()


def read_rotors(
    rd: SceneReader, features: frozenset[str], init: dict[str, Any], inertia: np.ndarray
) -> dict[str, Rotor]:
    """The [rotors.<name>] tables: axis (3 numbers, body frame, unit length within
    AXIS_NORM_TOL, normalised), J (kg·m², > 0) and the start rate initial.Omega_<name> (rad/s,
    default 0). inertia: the whole body's, rotors included (kg·m², body, about the point it
    turns about); I − Σ J g gᵀ must stay positive definite (docs/theory.md §8.1)."""
    sec = rd.data.get("rotors", {})
    if not isinstance(sec, dict):
        raise rd.fail("rotors", f"must be tables [rotors.<name>], got {sec!r}")
    if not sec:
        return {}
    if len(sec) > MAX_ROTORS:  # before any table is read
        check_scene_limits(rd.path, 0, {}, len(sec))
    for feat in EXCLUDED_FEATURES:
        if feat in features:
            raise rd.fail(
                "rotors", f"rotors exclude features.{feat} (its bearing torque does not include the rotors' reaction)"
            )
    rotors: dict[str, Rotor] = {}
    remaining = np.array(inertia, dtype=float)
    for name, spec in sec.items():
        fld = f"rotors.{name}"
        if not (name.isidentifier() and name.isascii()) or name in RESERVED_NAMES or name.startswith("abs_"):
            raise rd.fail(
                fld,
                "the rotor name must be an ASCII identifier, not one of "
                f"{', '.join(sorted(RESERVED_NAMES))} nor starting with abs_ (its variables Omega_<name>, "
                f"Omega_abs_<name>, h_<name> would clash with others), got {name!r}",
            )
        if not isinstance(spec, dict) or set(spec) != {"axis", "J"}:
            raise rd.fail(
                fld,
                "must be a table with axis = [x, y, z] (unit vector, body frame) and J (axial inertia, kg m^2, > 0), "
                f"got {spec!r}",
            )
        axis = rd.vector(f"{fld}.axis", spec["axis"], 3)
        n = float(np.linalg.norm(axis))
        if not abs(n - 1.0) <= AXIS_NORM_TOL:
            raise rd.fail(
                f"{fld}.axis",
                f"must be a unit vector (|axis| within {AXIS_NORM_TOL:g} of 1; it is normalised within that, "
                f"refused beyond), got |axis| = {n:.12g}",
            )
        axis = axis / n
        J = rd.number(f"{fld}.J", spec["J"], positive=True)
        remaining = remaining - J * np.outer(axis, axis)
        smallest = float(np.linalg.eigvalsh(0.5 * (remaining + remaining.T))[0])
        if not smallest > 0.0:
            raise rd.fail(
                f"{fld}.J",
                f"J = {J:g} kg m^2 leaves the body without a positive definite inertia: I - sum J g g^T over the "
                f"rotors up to {name!r} has smallest eigenvalue {smallest:.6g} kg m^2 (the scene's inertia is the "
                "whole body's, rotors included, so each J must be smaller than the inertia about its axis)",
            )
        key = f"Omega_{name}"
        Omega0 = rd.number(f"initial.{key}", init[key]) if key in init else 0.0
        rotors[name] = Rotor(axis, J, Omega0)
    return rotors
