"""Scene-file rules of the rotors (the gyrostat): [rotors.<name>] tables, their start rates and their input schedules.

`read_rotors` reads each ``[rotors.<name>]`` (a spin axis in the body frame and an axial
inertia) and its start rate ``initial.Omega_<name>``, and refuses inertias that leave the
rest of the body without a positive definite inertia (docs/theory.md §8.1). Called by
``modelsrc.scene.load_scene`` through the rotors' descriptor (feature.py) with its reader,
so every error names the file, the field and what is allowed. `Rotor` is part of the
scene's data (modelsrc.scene_data), so this module imports nothing of the model.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...scene_inputs import InputSpec, derivative_schedule
from ...scene_limits import MAX_ROTORS, check_scene_limits
from ...scene_reader import SceneReader

# An axis this close to unit length is normalised; farther off it is refused, so that a
# typo (an axis of length 2, or 0) is not silently turned into another direction.
AXIS_NORM_TOL = 1e-9
# Features a body with rotors cannot have: a prescribed rate holds ω, but the rotor
# reaction −Σ g u is a torque on the body the bearing torque would have to absorb; the
# output tau_bearing does not include it (a later increment of issue 28).
EXCLUDED_FEATURES = ("prescribed_rate",)
# Rotor names whose variables would repeat others': h_<name> the step report's h_max, h_last,
# h_next; a name abs_<x> makes Omega_abs_<x>, the absolute-rate output of a rotor <x>.
RESERVED_NAMES = frozenset({"max", "last", "next"})


# A rotor's modes (docs/theory.md §8.5): "torque" (the motor torque u is the input, the
# rate Ω a state) or "speed" (Ω and its derivative are inputs, the motor torque an output).
MODES = ("torque", "speed")
# The keys a [rotors.<name>] table takes; the propeller keys (position, k_f, k_m: thrust
# k_f Ω² along the axis at the position, drag torque −k_m Ω|Ω|... §8.6) need speed mode and
# features.translation.
ROTOR_KEYS = frozenset({"axis", "J", "mode", "position", "k_f", "k_m"})
PROPELLER_KEYS = frozenset({"position", "k_f", "k_m"})


@dataclass(frozen=True)
class Rotor:
    """A rotor of the gyrostat: axis g (unit vector, body frame), axial inertia J (kg·m², about
    its axis) and start rate Omega0 (rad/s, relative to the body, positive right-handed about g;
    0 in speed mode, where Ω is an input); mode "torque" or "speed" (docs/theory.md §8.5);
    a propeller (speed mode, translation): its position (m, body frame, from the centre of
    mass), thrust coefficient k_f (N·s²: thrust k_f Ω² along g) and drag coefficient k_m
    (N·m·s²: drag torque −k_m Ω² sgn(Ω) g on the body) (§8.6)."""

    axis: np.ndarray
    J: float
    Omega0: float
    mode: str = "torque"
    position: np.ndarray | None = None
    k_f: float = 0.0
    k_m: float = 0.0

    @property
    def speed(self) -> bool:
        """True in speed mode: Ω is an input, the motor torque an output."""
        return self.mode == "speed"

    @property
    def propeller(self) -> bool:
        """True when the rotor makes thrust (a position is given)."""
        return self.position is not None


def rotor_start_keys(data: Mapping[str, Any]) -> frozenset[str]:
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
        if not (name.isidentifier() and name.isascii()) or name in RESERVED_NAMES or name.startswith(("abs_", "dot_")):
            raise rd.fail(
                fld,
                "the rotor name must be an ASCII identifier, not one of "
                f"{', '.join(sorted(RESERVED_NAMES))} nor starting with abs_ or dot_ (its variables Omega_<name>, "
                f"Omega_abs_<name>, Omega_dot_<name>, h_<name> would clash with others), got {name!r}",
            )
        if not isinstance(spec, dict) or not {"axis", "J"} <= set(spec) <= ROTOR_KEYS:
            raise rd.fail(
                fld,
                "must be a table with axis = [x, y, z] (unit vector, body frame) and J (axial inertia, kg m^2, > 0), "
                'optionally mode = "torque" or "speed" and, in speed mode with features.translation, '
                f"position = [x, y, z] (m, body), k_f (N s^2), k_m (N m s^2), got {spec!r}",
            )
        mode = spec.get("mode", "torque")
        if mode not in MODES:
            raise rd.fail(f"{fld}.mode", f"must be one of {', '.join(MODES)}, got {mode!r}")
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
        if mode == "speed" and key in init:
            raise rd.fail(
                f"initial.{key}",
                f"rotor {name} is in speed mode: Omega_{name} is an input; give its schedule in [inputs] "
                "(a constant or a harmonic), not a start value",
            )
        Omega0 = rd.number(f"initial.{key}", init[key]) if key in init else 0.0
        prop = {k: spec[k] for k in PROPELLER_KEYS if k in spec}
        if prop and (mode != "speed" or "translation" not in features or "position" not in prop):
            raise rd.fail(
                f"{fld}.{sorted(prop)[0]}",
                'a propeller (position, k_f, k_m) needs mode = "speed", features.translation = true and a '
                f"position; rotor {name} has mode {mode!r}"
                + ("" if "translation" in features else ", no translation")
                + ("" if "position" in prop else ", no position"),
            )
        position = rd.vector(f"{fld}.position", prop["position"], 3) if prop else None
        k_f = rd.number(f"{fld}.k_f", prop["k_f"], nonneg=True) if "k_f" in prop else 0.0
        k_m = rd.number(f"{fld}.k_m", prop["k_m"], nonneg=True) if "k_m" in prop else 0.0
        rotors[name] = Rotor(axis, J, Omega0, mode, position, k_f, k_m)
    return rotors


def rotor_file_inputs(rotors: Mapping[str, Rotor]) -> frozenset[str]:
    """The [inputs] keys the rotors allow: u_<name> of a torque-mode rotor, Omega_<name> of a
    speed-mode one (its derivative Omega_dot_<name> is derived, `with_speed_derivatives`)."""
    return frozenset(f"Omega_{n}" if r.speed else f"u_{n}" for n, r in rotors.items())


def check_rotor_input(rd: SceneReader, var: str, value: Any) -> None:
    """Refuse a table as the schedule of a speed-mode rotor's rate (docs/theory.md §8.5)."""
    if var.startswith("Omega_") and isinstance(value, list):
        raise rd.fail(
            f"inputs.{var}",
            "a speed-mode rotor's rate takes a constant or a harmonic, not a table: a step in its speed would need "
            "an infinite motor torque (drive it from an input function with its derivative Omega_dot instead)",
        )


def with_speed_derivatives(inputs: dict[str, InputSpec]) -> dict[str, InputSpec]:
    """The schedules with Omega_dot_<name> derived from every Omega_<name> given (a
    speed-mode rotor's rate and its derivative, docs/theory.md §8.5)."""
    out = {k: v for k, v in inputs.items() if not k.startswith("Omega_dot_")}
    for k, v in inputs.items():
        if k.startswith("Omega_") and not k.startswith("Omega_dot_"):
            out[f"Omega_dot_{k.removeprefix('Omega_')}"] = derivative_schedule(v)
    return out
