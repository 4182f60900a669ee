"""Scene-file rules of the rotors (the gyrostat): [rotors.<name>] tables, their start rates and their input schedules.

`read_rotors` reads each ``[rotors.<name>]`` (a spin axis in the body frame and an axial
inertia) and its start rate ``initial.Omega_<name>``, and refuses inertias that leave the
rest of the body without a positive definite inertia (docs/theory.md §8.1). Called by
``modelsrc.scene.load_scene`` through the rotors' descriptor (feature.py) with its reader,
so every error names the file, the field and what is allowed. `Rotor` is part of the
scene's data (modelsrc.scene_data), so this module imports nothing of the model.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...scene_inputs import InputSpec, derivative_schedule
from ...scene_limits import MAX_ROTORS, check_scene_limits
from ...scene_reader import UNIT_LENGTH_TOL, SceneReader

# An axis this close to unit length is normalised; farther off it is refused, so that a
# typo (an axis of length 2, or 0) is not silently turned into another direction.
AXIS_NORM_TOL = UNIT_LENGTH_TOL  # the start quaternion's rule too
# Features a body with rotors cannot have: a prescribed rate holds ω, but the rotor
# reaction −Σ g u is a torque on the body the bearing torque would have to absorb; the
# output tau_bearing does not include it (a later increment of issue 28).
EXCLUDED_FEATURES = ("prescribed_rate",)
# Rotor names whose variables would repeat others': h_<name> the step report's h_max, h_last,
# h_next; a name abs_<x> makes Omega_abs_<x>, the absolute-rate output of a rotor <x>.
RESERVED_NAMES = frozenset({"max", "last", "next"})


# The keys every [rotors.<name>] table takes; the propeller keys (position, k_f, k_m: thrust
# k_f Ω² along the axis at the position, drag torque −k_m Ω|Ω|... §8.6) need a mode that
# allows a propeller and features.translation; a mode may take keys of its own (ModeRules.keys).
ROTOR_KEYS = frozenset({"axis", "J", "mode", "position", "k_f", "k_m"})
PROPELLER_KEYS = frozenset({"position", "k_f", "k_m"})
# Name prefixes a rotor may not take: Omega_abs_<x>, Omega_dot_<x> are the variables of a rotor <x>.
RESERVED_PREFIXES = ("abs_", "dot_")


@dataclass(frozen=True)
class ModeRules:
    """What a rotor mode takes in the scene file (docs/theory.md §8.5). state: its rate Ω is a
    state (a start value initial.Omega_<name> is allowed) rather than an input; propeller: it
    may carry a propeller (§8.6); keys: its own numbers in [rotors.<name>] (each required,
    > 0, kept in Rotor.settings); inputs: the keys of [inputs] it takes, "{}" standing for
    the rotor's name; no_tables: its inputs take a constant or a harmonic, not a table;
    reserved: name prefixes its inputs' names make unavailable to rotors (as abs_, dot_)."""

    name: str
    state: bool
    propeller: bool = False
    keys: frozenset[str] = frozenset()
    inputs: tuple[str, ...] = ()
    no_tables: bool = False
    reserved: tuple[str, ...] = ()


# The modes of docs/theory.md §8.5: "torque" (the motor torque u is the input, the rate Ω a
# state) and "speed" (Ω and its derivative are inputs, the motor torque an output); a mode
# module of this folder adds more (feature.py, modes.py).
TORQUE = ModeRules("torque", state=True, inputs=("u_{}",))
SPEED = ModeRules("speed", state=False, propeller=True, inputs=("Omega_{}",), no_tables=True)
BUILT_IN_MODES = {m.name: m for m in (TORQUE, SPEED)}


@dataclass(frozen=True)
class Rotor:
    """A rotor of the gyrostat: axis g (unit vector, body frame), axial inertia J (kg·m², about
    its axis) and start rate Omega0 (rad/s, relative to the body, positive right-handed about g;
    0 in speed mode, where Ω is an input); mode "torque" or "speed" (docs/theory.md §8.5);
    a propeller (speed mode, translation): its position (m, body frame, from the centre of
    mass), thrust coefficient k_f (N·s²: thrust k_f Ω² along g) and drag coefficient k_m
    (N·m·s²: drag torque −k_m Ω² sgn(Ω) g on the body) (§8.6); settings: the numbers its
    mode takes of its own (ModeRules.keys)."""

    axis: np.ndarray
    J: float
    Omega0: float
    mode: str = "torque"
    position: np.ndarray | None = None
    k_f: float = 0.0
    k_m: float = 0.0
    settings: Mapping[str, float] = field(default_factory=dict)

    @property
    def speed(self) -> bool:
        """True in speed mode: Ω is an input, the motor torque an output."""
        return self.mode == "speed"

    @property
    def propeller(self) -> bool:
        """True when the rotor makes thrust (a position is given)."""
        return self.position is not None


def _quoted(names: Iterable[str]) -> str:
    """ "a" or "b" ... (the values a key may take, as a scene file writes them)."""
    return " or ".join(f'"{n}"' for n in names)


def rotor_start_keys(data: Mapping[str, Any]) -> frozenset[str]:
    """The [initial] keys the scene's rotors allow: Omega_<name> for every [rotors.<name>]."""
    sec = data.get("rotors", {})
    return frozenset(f"Omega_{n}" for n in sec) if isinstance(sec, dict) else frozenset()


def read_rotors(
    rd: SceneReader,
    features: frozenset[str],
    init: dict[str, Any],
    inertia: np.ndarray,
    modes: Mapping[str, ModeRules] = BUILT_IN_MODES,
) -> dict[str, Rotor]:
    """The [rotors.<name>] tables: axis (3 numbers, body frame, unit length within
    AXIS_NORM_TOL, normalised), J (kg·m², > 0), the mode (one of `modes`, default "torque")
    with its own keys, and the start rate initial.Omega_<name> (rad/s, default 0) of a mode
    whose rate is a state. inertia: the whole body's, rotors included (kg·m², body, about the
    point it turns about); I − Σ J g gᵀ must stay positive definite (docs/theory.md §8.1)."""
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
    reserved = RESERVED_PREFIXES + tuple(p for m in modes.values() for p in m.reserved)
    keys = ROTOR_KEYS.union(*(m.keys for m in modes.values()))
    propellers = [m.name for m in modes.values() if m.propeller]
    propeller_modes = " or ".join(propellers)
    mode_keys = "".join(f", in {m.name} mode {', '.join(sorted(m.keys))}" for m in modes.values() if m.keys)
    for name, spec in sec.items():
        fld = f"rotors.{name}"
        if not (name.isidentifier() and name.isascii()) or name in RESERVED_NAMES or name.startswith(reserved):
            raise rd.fail(
                fld,
                "the rotor name must be an ASCII identifier, not one of "
                f"{', '.join(sorted(RESERVED_NAMES))} nor starting with {' or '.join(reserved)} (its variables "
                f"Omega_<name>, Omega_abs_<name>, Omega_dot_<name>, h_<name> would clash with others), got {name!r}",
            )
        if not isinstance(spec, dict) or not {"axis", "J"} <= set(spec) <= keys:
            raise rd.fail(
                fld,
                "must be a table with axis = [x, y, z] (unit vector, body frame) and J (axial inertia, kg m^2, > 0), "
                f"optionally mode = {_quoted(modes)} and, in {propeller_modes} mode with features.translation, "
                f"position = [x, y, z] (m, body), k_f (N s^2), k_m (N m s^2){mode_keys}, got {spec!r}",
            )
        mode = spec.get("mode", "torque")
        if mode not in modes:
            raise rd.fail(f"{fld}.mode", f"must be one of {', '.join(modes)}, got {mode!r}")
        rules = modes[mode]
        foreign = sorted(set(spec) - ROTOR_KEYS - rules.keys)
        if foreign:
            raise rd.fail(f"{fld}.{foreign[0]}", f"is not a key of mode {mode!r} (its keys: "
                          f"{', '.join(sorted(ROTOR_KEYS | rules.keys))})")  # fmt: skip
        for k in sorted(rules.keys - set(spec)):
            raise rd.fail(f"{fld}.{k}", f"required in mode {mode!r} (a number > 0)")
        settings = {k: rd.parameter(f"{fld}.{k}", spec[k], positive=True) for k in sorted(rules.keys)}
        axis = rd.vector(f"{fld}.axis", spec["axis"], 3)
        n = float(np.linalg.norm(axis))
        if not abs(n - 1.0) <= AXIS_NORM_TOL:
            raise rd.fail(
                f"{fld}.axis",
                f"must be a unit vector (|axis| within {AXIS_NORM_TOL:g} of 1; it is normalised within that, "
                f"refused beyond), got |axis| = {n:.12g}",
            )
        axis = axis / n
        J = rd.parameter(f"{fld}.J", spec["J"], positive=True)
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
        if not rules.state and key in init:
            raise rd.fail(
                f"initial.{key}",
                f"rotor {name} is in {mode} mode: Omega_{name} is an input; give its schedule in [inputs] "
                "(a constant or a harmonic), not a start value",
            )
        Omega0 = rd.number(f"initial.{key}", init[key]) if key in init else 0.0
        prop = {k: spec[k] for k in PROPELLER_KEYS if k in spec}
        if prop and (not rules.propeller or "translation" not in features or "position" not in prop):
            raise rd.fail(
                f"{fld}.{sorted(prop)[0]}",
                f"a propeller (position, k_f, k_m) needs mode = {_quoted(propellers)}, "
                f"features.translation = true and a position; rotor {name} has mode {mode!r}"
                + ("" if "translation" in features else ", no translation")
                + ("" if "position" in prop else ", no position"),
            )
        position = (
            np.array(
                [
                    rd.parameter(f"{fld}.position[{i + 1}]", v)
                    for i, v in enumerate(rd.vector(f"{fld}.position", prop["position"], 3))
                ]
            )
            if prop
            else None
        )
        k_f = rd.parameter(f"{fld}.k_f", prop["k_f"], nonneg=True) if "k_f" in prop else 0.0
        k_m = rd.parameter(f"{fld}.k_m", prop["k_m"], nonneg=True) if "k_m" in prop else 0.0
        rotors[name] = Rotor(axis, J, Omega0, mode, position, k_f, k_m, settings)
    return rotors


def rotor_file_inputs(rotors: Mapping[str, Rotor], modes: Mapping[str, ModeRules] = BUILT_IN_MODES) -> frozenset[str]:
    """The [inputs] keys the rotors allow: u_<name> of a torque-mode rotor, Omega_<name> of a
    speed-mode one (its derivative Omega_dot_<name> is derived, `with_speed_derivatives`),
    those of the other modes (ModeRules.inputs)."""
    return frozenset(p.format(n) for n, r in rotors.items() for p in modes[r.mode].inputs)


def check_rotor_input(
    rd: SceneReader, var: str, value: Any, rotors: Mapping[str, Rotor], modes: Mapping[str, ModeRules] = BUILT_IN_MODES
) -> None:
    """Refuse a table as the schedule of a speed-mode rotor's rate (docs/theory.md §8.5), or of
    any input of a mode that takes no tables."""
    held = {p.format(n) for n, r in rotors.items() if modes[r.mode].no_tables for p in modes[r.mode].inputs}
    if var in held and isinstance(value, list):
        raise rd.fail(
            f"inputs.{var}",
            "a speed-mode rotor's rate takes a constant or a harmonic, not a table: a step in its speed would need "
            "an infinite motor torque (drive it from an input function with its derivative Omega_dot instead)",
        )


# A speed-mode rotor's two inputs (docs/theory.md §8.5): its rate Omega_<name> (rad/s,
# relative to the body) and the rate's time derivative Omega_dot_<name> (rad/s²), which a
# run derives from the rate's schedule. The one place of that naming rule: the scene's
# derived inputs, their refusal and the trim's test of a held speed use these.
SPEED_PREFIX, SPEED_RATE_PREFIX = "Omega_", "Omega_dot_"


def speed_rate_name(rotor: str) -> str:
    """Omega_dot_<rotor>: the input holding the derivative of a speed-mode rotor's rate."""
    return f"{SPEED_RATE_PREFIX}{rotor}"


def speed_of_rate(name: str) -> str | None:
    """Omega_<rotor> of the derivative input Omega_dot_<rotor> (`speed_rate_name`); None for
    any other name."""
    return SPEED_PREFIX + name.removeprefix(SPEED_RATE_PREFIX) if name.startswith(SPEED_RATE_PREFIX) else None


def with_speed_derivatives(
    inputs: dict[str, InputSpec], rotors: Mapping[str, Rotor] | None = None
) -> dict[str, InputSpec]:
    """The schedules with Omega_dot_<name> derived from every Omega_<name> given (a
    speed-mode rotor's rate and its derivative, docs/theory.md §8.5): of the speed-mode
    `rotors`, or (None) of every Omega_<name> but the Omega_dot_ ones."""

    def speed_rate(k: str) -> bool:
        if rotors is None:
            return k.startswith(SPEED_PREFIX) and speed_of_rate(k) is None
        return any(k == f"{SPEED_PREFIX}{n}" for n, r in rotors.items() if r.speed)

    out = {k: v for k, v in inputs.items() if speed_of_rate(k) is None}
    for k, v in inputs.items():
        if speed_rate(k):
            out[speed_rate_name(k.removeprefix(SPEED_PREFIX))] = derivative_schedule(v)
    return out
