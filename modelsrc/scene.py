"""Scene files: a rigid body, the features it uses, its start state and experiment.

A scene is data (`modelsrc/scenes/<name>.toml`, format in docs/user_guide.md §2);
`load_scene` reads and validates one and returns a `Scene`. Every error names the
file, the field and what is allowed.
"""

from __future__ import annotations

import dataclasses
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ModelInputError
from .methods import DEFAULT_TOLERANCE, METHODS
from .quaternion import quat_from_euler_zxz
from .scene_body import diagonal_about_rotation_point, read_inertia
from .scene_central import EXCLUDED_METHODS as CENTRAL_EXCLUDED_METHODS
from .scene_central import read_central_gravity
from .scene_inputs import (
    InputSpec,
    derivative_schedule,
    hold_inputs,
    input_at,
    input_component,
    input_mean,
    input_start,
    input_width,
    parse_input,
    switch_times,
    varies_in_step,
)
from .scene_limits import check_scene_limits, check_table_rows
from .scene_motion import ForcePoint, check_feature_rules, read_force_points, read_gravity, read_start
from .scene_orbit import EXCLUDED_METHODS as ORBIT_EXCLUDED_METHODS
from .scene_orbit import read_orbit
from .scene_reader import SceneReader
from .scene_rotors import EXCLUDED_METHODS, Rotor, read_rotors, rotor_start_keys

SCENE_DIR = Path(__file__).resolve().parent / "scenes"

FEATURES = (
    "torque_body",
    "torque_world",
    "gravity",
    "friction",
    "prescribed_rate",
    "translation",
    "force_body",
    "force_world",
    "moving_pivot",
    "orbit",
    "gravity_gradient",
    "central_gravity",
)
# Features that put a torque on the body about the point it turns about (the centre of
# mass of a free body, else the pivot). A scene with none of them, and no force point
# off the centre of mass, is torque-free (docs/theory.md §2.3): |L| and the rotational
# energy are conserved and L is constant in the world frame. Gravity on a free body
# (translation) acts at the centre of mass and is no torque about it; forces through the
# centre of mass (force_body, force_world) push without turning (docs/theory.md §7.1).
# This is the one place that decides it (Scene.torque_free).
TORQUE_FEATURES = frozenset(
    {
        "torque_body",
        "torque_world",
        "gravity",
        "friction",
        "prescribed_rate",
        "moving_pivot",
        "gravity_gradient",
        "central_gravity",  # its gravity-gradient torque (docs/theory.md §9.7); conservative: E_total is kept
    }
)
# Features whose torques or forces do work that is not the change of a potential: without
# them (and without force points) the energy E_total is conserved (gravity is
# conservative; a prescribed rate keeps ω and E; a moving pivot's force does work; the
# gravity-gradient torque works through the orbit's turning field: what it conserves is the
# Jacobi integral E_jacobi in the orbit frame, docs/theory.md §9.3).
WORKING_FEATURES = frozenset(
    {"torque_body", "torque_world", "friction", "force_body", "force_world", "moving_pivot", "gravity_gradient"}
)
# Features that move the reference point (centre of mass or pivot): their states follow q, w_body.
MOTION_FEATURES = frozenset({"translation", "moving_pivot"})
# Outputs a scene may request; the states (q, w_body, and x_cm, v_cm of a free body or
# x_pivot, v_pivot of a moving pivot) are always outputs. "sensor" adds
# sensor_r/sensor_v/sensor_a of the point [sensor].point; "tau_bearing" (prescribed_rate
# scenes) the torque that holds the rate; x_cm, v_cm, a_cm, p need translation or a moving
# pivot, f_pivot a moving pivot.
OUTPUTS = (
    "q",
    "w_body",
    "w_world",
    "euler_zxz",
    "E_kin",
    "E_total",
    "L_world",
    "L_body",
    "sensor",
    "tau_bearing",
    "x_cm",
    "v_cm",
    "a_cm",
    "p",
    "f_pivot",
)
STATE_OUTPUTS = ("q", "w_body")
# Outputs that exist only with some features (any one of them).
OUTPUT_NEEDS = {
    "tau_bearing": frozenset({"prescribed_rate"}),
    "x_cm": MOTION_FEATURES,
    "v_cm": MOTION_FEATURES,
    "a_cm": MOTION_FEATURES,
    "p": MOTION_FEATURES,
    "f_pivot": frozenset({"moving_pivot"}),
}
INPUT_OF_FEATURE = {
    "torque_body": "tau_body",
    "torque_world": "tau_world",
    "force_body": "f_body",
    "force_world": "f_world",
    "moving_pivot": "a_pivot",
}
# Names a force point may not take: its input f_<name> and parameter r_<name> would
# clash with other variables.
RESERVED_POINT_NAMES = frozenset({"body", "world", "pivot", "cm", "sensor"})
QUAT_NORM_TOL = 1e-6  # a start quaternion this close to unit norm is normalised, else refused
# The name becomes the FMU's modelIdentifier: the archive's and the binary's file names and
# the prefix of its C functions (FMI 3.0 §2.4.1: a C identifier), so ASCII and short
# enough for every file system and for the extraction paths importers build from it.
MAX_NAME_LENGTH = 64
# Device names Windows reserves in every folder, whatever the case and extension: a file
# con.dll or NUL.fmu cannot be created or opened there ("Naming Files, Paths, and
# Namespaces", Microsoft Learn), and the FMU's archive and binary carry the name.
WINDOWS_RESERVED_NAMES = frozenset(
    {"CON", "PRN", "AUX", "NUL", *(f"COM{i}" for i in range(1, 10)), *(f"LPT{i}" for i in range(1, 10))}
)
# A scene file is a few hundred bytes; input tables of 1e5 rows stay below this.
MAX_SCENE_BYTES = 16 * 2**20

_TOP_KEYS = {
    "name",
    "description",
    "outputs",
    "body",
    "features",
    "gravity",
    "friction",
    "initial",
    "inputs",
    "experiment",
    "sensor",
    "forces",
    "rotors",
    "orbit",
    "central_gravity",
}
_SECTION_KEYS = {
    "body": {"principal_moments", "inertia", "mass", "inertia_about"},
    "features": set(FEATURES),
    "gravity": {"r_cm", "g"},
    "friction": {"c"},
    "initial": {"w_body", "q", "euler_zxz", "x_cm", "v_cm", "x_pivot", "v_pivot"},
    "inputs": set(INPUT_OF_FEATURE.values()),
    "sensor": {"point"},
    "experiment": {"stop_time", "step", "h_max", "tolerance", "methods", "method"},
    "orbit": {"rate"},
    "central_gravity": {"mu"},
}


@dataclass
class Scene:
    """A validated scene. SI units; vectors in the frame their name says.

    inertia: 3×3 about the centre of mass (kg·m², body frame); principal: True when the
    scene gives principal moments (the FMU then has 3 inertia parameters, not 9);
    pivot_inertia: the tensor as given about the pivot (`inertia_about = "pivot"`, the
    FMU's parameters then) or None; diagonal: the inertia about the point the body turns
    about is diagonal (the methods that need principal axes may be compiled in);
    r_cm: pivot -> centre of mass (m, body); g: gravity (m/s², world); c_friction
    (N·m·s/rad); w0 (rad/s, body); q0 unit quaternion body -> world (scalar first);
    x0, v0: start position (m) and velocity (m/s), world frame, of the centre of mass
    (translation) or of the pivot (moving_pivot); force_points: name -> ForcePoint;
    inputs: name -> constant vector, table rows [t, x, y, z] held piecewise constant, or
    a Harmonic (modelsrc.scene_inputs);
    sensor_point: body-fixed point (m, body frame, from the point the body turns about:
    the pivot, else the centre of mass) whose position, velocity, acceleration are output;
    stop_time, step (communication step), h_max (largest internal step, 0: no cap), all
    in s; tolerance: relative error per second of error-controlled stepping, 0 for fixed
    steps (docs/theory.md §5.4, §5.5); methods: the integrators compiled into the FMU,
    method: the default one; rotors: name -> Rotor (modelsrc.scene_rotors, the gyrostat of
    docs/theory.md §8), in value-reference order; orbit_rate: the rate n (rad/s) of the
    circular orbit (features.orbit, docs/theory.md §9), 0.0 without one; mu: the central
    body's G M (m³/s², at the world origin; features.central_gravity, §9.7), 0.0 without.
    """

    name: str
    description: str
    path: Path
    inertia: np.ndarray
    principal: bool
    features: frozenset[str]
    outputs: tuple[str, ...]
    w0: np.ndarray
    q0: np.ndarray
    mass: float = 1.0
    r_cm: np.ndarray = field(default_factory=lambda: np.zeros(3))
    g: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -9.81]))
    c_friction: float = 0.0
    x0: np.ndarray = field(default_factory=lambda: np.zeros(3))
    v0: np.ndarray = field(default_factory=lambda: np.zeros(3))
    force_points: dict[str, ForcePoint] = field(default_factory=dict)
    inputs: dict[str, InputSpec] = field(default_factory=dict)
    sensor_point: np.ndarray = field(default_factory=lambda: np.zeros(3))
    stop_time: float = 10.0
    step: float = 1e-2
    h_max: float = 0.0
    tolerance: float = DEFAULT_TOLERANCE
    methods: tuple[str, ...] = ()
    method: str = "rk8"
    pivot_inertia: np.ndarray | None = None
    diagonal: bool = False
    rotors: dict[str, Rotor] = field(default_factory=dict)
    orbit_rate: float = 0.0
    mu: float = 0.0

    def has(self, feature: str) -> bool:
        """True when the scene uses `feature` (one of FEATURES)."""
        return feature in self.features

    @property
    def torque_free(self) -> bool:
        """No torque acts on the body about the point it turns about: none of
        TORQUE_FEATURES (gravity excepted on a free body, where it acts at the centre of
        mass) and no force point off the centre of mass (a prescribed rate needs a bearing
        torque, so it is not torque-free either)."""
        torques = self.features & TORQUE_FEATURES
        if self.has("translation"):
            torques = torques - {"gravity"}
        propellers = any(r.propeller for r in self.rotors.values())  # thrust moments and drag (§8.6)
        return not torques and not propellers and not any(np.any(fp.point != 0.0) for fp in self.force_points.values())

    @property
    def conserves_energy(self) -> bool:
        """E_total (kinetic + potential) is conserved: none of WORKING_FEATURES, no force
        point, no speed-mode rotor and no motor-torque schedule (motors do work, §8.2, §8.5)."""
        motors = any(r.speed for r in self.rotors.values()) or any(k.startswith("u_") for k in self.inputs)
        return not (self.features & WORKING_FEATURES) and not self.force_points and not motors

    @property
    def exact_flow(self) -> bool:
        """exact_free integrates the scene exactly at any step: it is torque-free and
        every force is constant in the world frame over a step (gravity, f_world), none
        turns with the body (f_body, body-frame force points) (docs/theory.md §7.4)."""
        body_forces = self.has("force_body") or any(fp.frame == "body" for fp in self.force_points.values())
        # the exact flow is the rigid body's in an inertial frame: no rotors, no orbit
        return self.torque_free and not body_forces and not self.rotors and not self.has("orbit")

    @property
    def fixed_step(self) -> float:
        """The internal step (s) of fixed stepping for this scene: h_max when the scene sets
        one, else a tenth of its communication step. The checks, the benchmark and the
        Exudyn references step with it (docs/theory.md §5.4)."""
        return fixed_step(self.h_max, self.step)

    @property
    def moves(self) -> bool:
        """The reference point (centre of mass or pivot) moves: translation or moving_pivot."""
        return bool(self.features & MOTION_FEATURES)

    def input_mean(self, name: str, t0: float, t1: float) -> np.ndarray:
        """Value of input `name` held over the communication step [t0, t1] (s): its mean
        there (modelsrc.scene_inputs); zeros for an input without a schedule."""
        spec = self.inputs.get(name)
        return np.zeros(input_width(name)) if spec is None else input_mean(spec, t0, t1)

    def input_at(self, name: str, t: float) -> np.ndarray:
        """The physical input `name` at time t (s) (modelsrc.scene_inputs.input_at); zeros
        for an input without a schedule."""
        spec = self.inputs.get(name)
        return np.zeros(input_width(name)) if spec is None else input_at(spec, t)

    @property
    def inputs_varying_in_step(self) -> list[str]:
        """The inputs that change inside a communication step (harmonics): the ones a
        driver of continuous inputs must give the FMU at its internal nodes."""
        return [n for n in self.input_names if varies_in_step(self.inputs.get(n))]

    def with_inputs_held(self, values: Mapping[str, float]) -> Scene:
        """The scene with every input component named in `values` ('f_thr_a[1]', 'a_pivot[3]')
        constant at its value for the whole run, replacing the scene's schedule for that
        component (modelsrc.scene_inputs.hold_component); other names are ignored."""
        names = self.input_names
        if not any(input_component(n, names) for n in values):
            return self
        return dataclasses.replace(self, inputs=with_speed_derivatives(hold_inputs(self.inputs, values, names)))

    def input_start(self, name: str) -> np.ndarray:
        """Value of input `name` at t = 0 (its start value); zeros without a schedule."""
        return input_start(self.inputs.get(name), input_width(name))

    def switch_times(self) -> list[float]:
        """Switching times (s) of the scene's input tables, sorted."""
        return sorted({t for spec in self.inputs.values() for t in switch_times(spec)})

    @property
    def input_names(self) -> list[str]:
        """The inputs of the scene's FMU, in value-reference order: the vectors (3
        components each), then each rotor's motor torque u_<name> (a scalar, N·m)."""
        names = [
            INPUT_OF_FEATURE[f] for f in ("torque_body", "torque_world", "force_body", "force_world") if self.has(f)
        ]
        names += [f"f_{n}" for n in self.force_points]
        names += ["a_pivot"] if self.has("moving_pivot") else []
        for n, r in self.rotors.items():  # speed mode: Omega and its derivative (docs/theory.md §8.5)
            names += [f"Omega_{n}", f"Omega_dot_{n}"] if r.speed else [f"u_{n}"]
        return names


def with_speed_derivatives(inputs: dict[str, InputSpec]) -> dict[str, InputSpec]:
    """The schedules with Omega_dot_<name> derived from every Omega_<name> given (a
    speed-mode rotor's rate and its derivative, docs/theory.md §8.5)."""
    out = {k: v for k, v in inputs.items() if not k.startswith("Omega_dot_")}
    for k, v in inputs.items():
        if k.startswith("Omega_") and not k.startswith("Omega_dot_"):
            out[f"Omega_dot_{k.removeprefix('Omega_')}"] = derivative_schedule(v)
    return out


def fixed_step(h_max: float, step: float) -> float:
    """A scene's internal step (s) of fixed stepping: h_max (s) when set (> 0), else a
    tenth of the communication step `step` (s) (Scene.fixed_step)."""
    return h_max if h_max > 0 else step / 10


def list_scenes() -> list[str]:
    """Names of the scenes shipped in modelsrc/scenes."""
    return sorted(p.stem for p in SCENE_DIR.glob("*.toml"))


def scene_path(name_or_path: str | Path) -> Path:
    """Resolve a scene name (shipped scene) or a path to a .toml file."""
    p = Path(name_or_path)
    if p.suffix == ".toml":
        if not p.is_file():
            raise ModelInputError(f"scene file {p} does not exist")
        return p
    candidate = SCENE_DIR / f"{name_or_path}.toml"
    if not candidate.is_file():
        raise ModelInputError(
            f"unknown scene {str(name_or_path)!r}; known scenes: {', '.join(list_scenes())} "
            "(or give a path to a .toml file)"
        )
    return candidate


def _xml_char(ch: str) -> bool:
    """A character XML 1.0 allows in a document (its production Char, §2.2)."""
    o = ord(ch)
    return o in (0x9, 0xA, 0xD) or 0x20 <= o <= 0xD7FF or 0xE000 <= o <= 0xFFFD or 0x10000 <= o <= 0x10FFFF


def _parse_file(path: Path) -> dict[str, Any]:
    """The TOML of a scene file; every way it can fail is a ModelInputError naming the file."""
    try:
        size = path.stat().st_size
        if size > MAX_SCENE_BYTES:
            raise ModelInputError(f"scene file {path}: {size} bytes, more than the {MAX_SCENE_BYTES} a scene may have")
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ModelInputError(f"scene file {path}: not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise ModelInputError(f"scene file {path}: not UTF-8 text (byte {exc.start}), as TOML must be") from None
    except RecursionError:
        raise ModelInputError(
            f"scene file {path}: arrays or tables nested too deeply to read (a scene needs 2 levels)"
        ) from None
    except OSError as exc:
        raise ModelInputError(f"scene file {path}: cannot be read: {exc.strerror or exc}") from None


def _name_and_description(rd: SceneReader, path: Path) -> tuple[str, str]:
    """The scene's name (an ASCII identifier of at most MAX_NAME_LENGTH characters) and its
    description (a string XML 1.0 can hold: it is written into modelDescription.xml)."""
    name = rd.data.get("name", path.stem)
    if not isinstance(name, str) or not (name.isascii() and name.isidentifier()):
        shown = name[:40] + "..." if isinstance(name, str) and len(name) > 40 else name
        raise rd.fail("name", f"must be an ASCII identifier (letters, digits, _; not a digit first), got {shown!r}")
    if len(name) > MAX_NAME_LENGTH:
        raise rd.fail(
            "name",
            f"has {len(name)} characters, at most {MAX_NAME_LENGTH} are allowed (it names the FMU's files and "
            "its C functions)",
        )
    if name.upper() in WINDOWS_RESERVED_NAMES:
        raise rd.fail(
            "name",
            f"{name!r} is a device name Windows reserves (CON, PRN, AUX, NUL, COM1-9, LPT1-9, in any case): the "
            "FMU's files carry the name, so it could not be unpacked there; choose another name",
        )
    description = rd.data.get("description", "")
    if not isinstance(description, str):
        raise rd.fail("description", f"must be a string, got {description!r}")
    for i, ch in enumerate(description):
        if not _xml_char(ch):
            raise rd.fail(
                "description",
                f"character {i} is U+{ord(ch):04X}, which XML 1.0 does not allow (modelDescription.xml holds the "
                "description): no control characters but tab, newline and carriage return",
            )
    return name, description


def load_scene(name_or_path: str | Path) -> Scene:
    """Read and validate a scene file (by shipped name or path). Raises ModelInputError."""
    path = scene_path(name_or_path)
    data = _parse_file(path)
    rd = SceneReader(path, data, _SECTION_KEYS)
    unknown = set(data) - _TOP_KEYS
    if unknown:
        raise rd.fail(sorted(unknown)[0], f"unknown key; allowed top-level keys: {', '.join(sorted(_TOP_KEYS))}")

    name, description = _name_and_description(rd, path)

    feats = rd.section("features")
    for k, v in feats.items():
        if not isinstance(v, bool):
            raise rd.fail(f"features.{k}", f"must be true or false, got {v!r}")
    features = frozenset(k for k, v in feats.items() if v)

    body = rd.section("body")
    check_feature_rules(rd, features)
    kw: dict[str, Any] = {"orbit_rate": read_orbit(rd, features)}  # its feature rules before the others' fields
    if "mass" in body:
        kw["mass"] = rd.number("body.mass", body["mass"], positive=True)
    else:
        for feat in ("gravity", "translation"):
            if feat in features:
                raise rd.fail("body.mass", f"required when features.{feat} is true (kg, > 0)")

    grav = rd.section("gravity")
    if "gravity" in features:
        kw.update(read_gravity(rd, features, grav))
    elif grav:
        raise rd.fail("gravity", "given but features.gravity is not true")

    kw["inertia"], principal, kw["pivot_inertia"] = read_inertia(
        rd, body, features, kw.get("mass", 1.0), kw.get("r_cm")
    )

    fric = rd.section("friction")
    if "friction" in features:
        if "c" not in fric:
            raise rd.fail("friction.c", "required when features.friction is true (N*m*s/rad, >= 0)")
        kw["c_friction"] = rd.number("friction.c", fric["c"], nonneg=True)
    elif fric:
        raise rd.fail("friction", "given but features.friction is not true")

    init = rd.section("initial", rotor_start_keys(data))
    if "w_body" not in init:
        raise rd.fail("initial.w_body", "required: initial angular velocity, 3 numbers (rad/s, body frame)")
    w0 = rd.vector("initial.w_body", init["w_body"], 3)
    if "q" in init and "euler_zxz" in init:
        raise rd.fail("initial", "give at most one of 'q' and 'euler_zxz'")
    if "euler_zxz" in init:
        q0 = quat_from_euler_zxz(*rd.vector("initial.euler_zxz", init["euler_zxz"], 3))
    else:
        q0 = rd.vector("initial.q", init.get("q", [1.0, 0.0, 0.0, 0.0]), 4)
        nq = float(np.linalg.norm(q0))
        if abs(nq - 1.0) > QUAT_NORM_TOL:
            raise rd.fail(
                "initial.q", f"must be a unit quaternion (|q| within {QUAT_NORM_TOL} of 1), got |q| = {nq:.9g}"
            )
        q0 = q0 / nq
    kw["mu"] = read_central_gravity(rd, features, init)  # its feature rules before the start's
    kw.update(read_start(rd, features, init))
    kw["force_points"] = read_force_points(rd, features, RESERVED_POINT_NAMES)
    kw["rotors"] = read_rotors(rd, features, init, kw["inertia"])

    point_inputs = {f"f_{n}" for n in kw["force_points"]}
    rotor_inputs = {f"Omega_{n}" if r.speed else f"u_{n}" for n, r in kw["rotors"].items()}
    inputs_sec = rd.section("inputs", frozenset(point_inputs | rotor_inputs))
    inputs: dict[str, InputSpec] = {}
    for var, val in inputs_sec.items():
        if var.startswith("Omega_") and isinstance(val, list):
            raise rd.fail(
                f"inputs.{var}",
                "a speed-mode rotor's rate takes a constant or a harmonic, not a table: a step in its speed would need "
                "an infinite motor torque (drive it from an input function with its derivative Omega_dot instead)",
            )
        owner = next((f for f, v in INPUT_OF_FEATURE.items() if v == var), None)
        if owner is not None and owner not in features:
            raise rd.fail(f"inputs.{var}", f"given but features.{owner} is not true")
        check_table_rows(rd, f"inputs.{var}", val)  # before each row is checked
        inputs[var] = parse_input(f"inputs.{var}", val, rd.vector, rd.number, rd.fail, input_width(var))

    inputs = with_speed_derivatives(inputs)
    if "prescribed_rate" in features and features & {"torque_body", "torque_world", "gravity", "friction"}:
        raise rd.fail(
            "features.prescribed_rate",
            "holds omega at its start value, so it excludes torque_body, "
            "torque_world, gravity and friction (the FMU outputs the torque that holds the rate instead)",
        )
    sensor = rd.section("sensor")
    if "point" in sensor:
        kw["sensor_point"] = rd.vector("sensor.point", sensor["point"], 3)

    default_outs = [o for o in OUTPUTS if o != "sensor" or "point" in sensor]
    default_outs = [o for o in default_outs if o not in OUTPUT_NEEDS or features & OUTPUT_NEEDS[o]]
    outs = data.get("outputs", default_outs)
    if not isinstance(outs, list) or any(o not in OUTPUTS for o in outs):
        raise rd.fail("outputs", f"must be a list drawn from {', '.join(OUTPUTS)}, got {outs!r}")
    outputs = tuple(o for o in OUTPUTS if o in set(outs) | set(STATE_OUTPUTS))
    if "sensor" in outputs and "point" not in sensor:
        raise rd.fail("sensor.point", "required when outputs include 'sensor' (3 numbers, m, body frame)")
    for o in outputs:
        if o in OUTPUT_NEEDS and not features & OUTPUT_NEEDS[o]:
            raise rd.fail("outputs", f"{o!r} needs features.{' or features.'.join(sorted(OUTPUT_NEEDS[o]))} = true")

    exp = rd.section("experiment")
    if "stop_time" in exp:
        kw["stop_time"] = rd.number("experiment.stop_time", exp["stop_time"], positive=True)
    if "step" in exp:
        kw["step"] = rd.number("experiment.step", exp["step"], positive=True)
    if "h_max" in exp:
        kw["h_max"] = rd.number("experiment.h_max", exp["h_max"], nonneg=True)
    if "tolerance" in exp:
        kw["tolerance"] = rd.number("experiment.tolerance", exp["tolerance"], nonneg=True)

    diagonal = diagonal_about_rotation_point(kw["inertia"], kw["pivot_inertia"], features, kw.get("r_cm"))
    kw["diagonal"] = diagonal
    allowed = [m.name for m in METHODS.values() if diagonal or not m.needs_principal]
    if kw["rotors"]:
        allowed = [m for m in allowed if m not in EXCLUDED_METHODS]
    if "orbit" in features:
        allowed = [m for m in allowed if m not in ORBIT_EXCLUDED_METHODS]
    if "central_gravity" in features:
        allowed = [m for m in allowed if m not in CENTRAL_EXCLUDED_METHODS]
    methods = exp.get("methods", allowed)
    if not isinstance(methods, list) or not methods or any(m not in allowed for m in methods):
        why = "splitting and exact_free need principal axes about the rotation point"
        if kw["rotors"]:
            why += "; with rotors they are refused: their flows are the rigid body's, without the rotor states"
        if "orbit" in features:
            why += "; in an orbit they are refused: their flows are the inertial rigid body's, without the orbit angle"
        if "central_gravity" in features:
            why += "; in a central field they are refused: their flows have no position-dependent force and torque"
        raise rd.fail(
            "experiment.methods",
            f"must be a non-empty list drawn from {', '.join(allowed)} ({why}), got {methods!r}",
        )
    kw["methods"] = tuple(m for m in METHODS if m in methods)
    method = exp.get("method")
    if method is not None and method not in kw["methods"]:
        raise rd.fail(
            "experiment.method", f"must be one of the scene's methods {', '.join(kw['methods'])}, got {method!r}"
        )

    scene = Scene(
        name=name,
        description=description,
        path=path,
        principal=principal,
        features=features,
        outputs=outputs,
        w0=w0,
        q0=q0,
        inputs=inputs,
        **kw,
    )
    scene.method = method if method is not None else default_method(scene)
    check_scene_limits(scene.path, len(scene.force_points), scene.inputs, len(scene.rotors))
    return scene


def default_method(scene: Scene) -> str:
    """The method a scene's FMU uses unless the scene names one: exact_free where it is
    exact (Scene.exact_flow: the torque-free body, exact at any step, so a fast spin costs
    one step per communication step and no round-off accumulates over millions of steps),
    else rk8 with error control at the default tolerance (docs/theory.md §5.5), else the
    first method compiled in."""
    if scene.exact_flow and "exact_free" in scene.methods:
        return "exact_free"
    return "rk8" if "rk8" in scene.methods else scene.methods[0]
