"""Scene files: a rigid body, the features it uses, its start state and experiment.

A scene is data (`modelsrc/scenes/<name>.toml`, format in docs/user_guide.md §2);
`load_scene` reads and validates one and returns a `Scene`: the body's parts here, each
feature's part by its readers, at their stage of the reading (modelsrc.registry,
docs/features.md). Every error names the file, the field and what is allowed.
"""

from __future__ import annotations

import dataclasses
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from . import registry, unit_mistakes
from .errors import ModelInputError
from .feature import ReadStage, SceneRead
from .features.free_motion.scene_file import RESERVED_POINT_NAMES, ForcePoint
from .features.rotors.scene_file import Rotor, speed_of_rate, with_speed_derivatives
from .methods import METHODS
from .quaternion import quat_from_euler_zxz
from .scene_body import diagonal_about_rotation_point, read_inertia
from .scene_data import SceneData, fixed_step
from .scene_inputs import (
    InputSpec,
    hold_inputs,
    input_component,
    input_width,
    parse_input,
    varies_in_step,
)
from .scene_limits import check_scene_limits, check_table_rows
from .scene_reader import UNIT_LENGTH_TOL, SceneReader
from .shipped_files import shipped_names, shipped_or_toml

# names other modules import from here; the scene's parts they name moved to their features
__all__ = [
    "FEATURES",
    "INPUT_OF_FEATURE",
    "MOTION_FEATURES",
    "OUTPUTS",
    "OUTPUT_NEEDS",
    "RESERVED_POINT_NAMES",
    "TORQUE_FEATURES",
    "WORKING_FEATURES",
    "ForcePoint",
    "Rotor",
    "Scene",
    "default_method",
    "fixed_step",
    "list_scenes",
    "load_scene",
    "scene_path",
    "with_speed_derivatives",
]

SCENE_DIR = Path(__file__).resolve().parent / "scenes"

# The flags of [features], each owned by one feature (modelsrc/features/).
FEATURES = registry.FLAGS
# Features that put a torque on the body about the point it turns about (the centre of
# mass of a free body, else the pivot). A scene with none of them, and no force point
# off the centre of mass, is torque-free (docs/theory.md §2.3): |L| and the rotational
# energy are conserved and L is constant in the world frame. Gravity on a free body
# (translation) acts at the centre of mass and is no torque about it; forces through the
# centre of mass (force_body, force_world) push without turning (docs/theory.md §7.1).
# Each feature decides it for itself (Feature.adds_torque, Scene.torque_free).
TORQUE_FEATURES = registry.TORQUE_FLAGS
# Features whose torques or forces do work that is not the change of a potential: without
# them (and without force points) the energy E_total is conserved (gravity is
# conservative; a prescribed rate keeps ω and E; a moving pivot's force does work; the
# gravity-gradient torque works through the orbit's turning field: what it conserves is the
# Jacobi integral E_jacobi in the orbit frame, docs/theory.md §9.3).
WORKING_FEATURES = registry.WORKING_FLAGS
# Features that move the reference point (centre of mass or pivot): their states follow q, w_body.
MOTION_FEATURES = registry.MOTION_FLAGS
# Outputs a scene may request; the states (q, w_body, and x_cm, v_cm of a free body or
# x_pivot, v_pivot of a moving pivot) are always outputs. The body's, then the features'
# (Feature.outputs): "sensor" adds sensor_r/sensor_v/sensor_a of the point [sensor].point;
# "tau_bearing" (prescribed_rate scenes) the torque that holds the rate; x_cm, v_cm, a_cm,
# p need translation or a moving pivot, f_pivot a moving pivot.
BODY_OUTPUTS = ("q", "w_body", "w_world", "euler_zxz", "E_kin", "E_total", "L_world", "L_body")
OUTPUTS = BODY_OUTPUTS + tuple(o.name for o in registry.OUTPUT_DECLARATIONS)
STATE_OUTPUTS = ("q", "w_body")
# Outputs that exist only with some features (any one of them).
OUTPUT_NEEDS = {o.name: o.needs for o in registry.OUTPUT_DECLARATIONS if o.needs}
INPUT_OF_FEATURE = registry.INPUT_OF_FLAG
QUAT_NORM_TOL = (
    UNIT_LENGTH_TOL  # a start quaternion this close to unit norm is normalised, else refused (as rotor axes)
)
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

# the body's tables and keys; the features add theirs (Feature.tables)
_BODY_TABLES = ("name", "description", "outputs", "body", "features", "initial", "inputs", "experiment")
_TOP_KEYS = set(_BODY_TABLES) | set(registry.TABLES)
_SECTION_KEYS = {
    "body": {"principal_moments", "inertia", "mass", "inertia_about"},
    "features": set(FEATURES),
    "initial": {"w_body", "q", "euler_zxz"},
    "inputs": set(INPUT_OF_FEATURE.values()),
    "experiment": {"stop_time", "step", "h_max", "tolerance", "methods", "method"},
    **{table: set(keys) for table, keys in registry.TABLE_KEYS.items()},
}


@dataclass
class Scene(SceneData):
    """A validated scene (its data: `scene_data.SceneData`) with what follows from the
    features it uses: torque-free, conserving energy, its inputs (modelsrc.registry)."""

    @property
    def torque_free(self) -> bool:
        """No torque acts on the body about the point it turns about: no feature adds one
        (TORQUE_FEATURES, gravity excepted on a free body, where it acts at the centre of
        mass; a force point off the centre of mass; a propeller; a prescribed rate needs a
        bearing torque, so it is not torque-free either)."""
        return registry.torque_free(self)

    @property
    def conserves_energy(self) -> bool:
        """E_total (kinetic + potential) is conserved: none of WORKING_FEATURES, no force
        point, no speed-mode rotor and no motor-torque schedule (motors do work, §8.2, §8.5)."""
        return registry.conserves_energy(self)

    @property
    def exact_flow(self) -> bool:
        """exact_free integrates the scene exactly at any step: it is torque-free and
        every force is constant in the world frame over a step (gravity, f_world), none
        turns with the body (f_body, body-frame force points) (docs/theory.md §7.4); the
        exact flow is the rigid body's in an inertial frame: no rotors, no orbit."""
        return self.torque_free and registry.keeps_exact_flow(self)

    @property
    def moves(self) -> bool:
        """The reference point (centre of mass or pivot) moves: translation or moving_pivot."""
        return bool(self.features & MOTION_FEATURES)

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
        held = hold_inputs(self.inputs, values, names)
        return dataclasses.replace(self, inputs=registry.derived_inputs(held, vars(self)))

    def refuse_derived_inputs(self, names: Iterable[str], where: str) -> None:
        """ModelInputError naming the first of `names` (variables a run is asked to set) that
        the run's driver re-derives from another input (a speed-mode rotor's Omega_dot_<name>,
        the derivative of its Omega_<name> schedule, docs/theory.md §8.5): a value given for it
        would be silently replaced (issue 39.5)."""
        derived = self.derived_input_names()
        for name in names:
            if name in derived:
                rate = speed_of_rate(name)
                raise ModelInputError(
                    f"{where}: {name} cannot be set: the run derives it from the schedule of {rate} (its time "
                    f"derivative, docs/theory.md §8.5); set {rate} instead"
                )

    def derived_input_names(self) -> frozenset[str]:
        """The inputs a run derives from others (a speed-mode rotor's Omega_dot_<name>, the
        time derivative of its Omega_<name> schedule, docs/theory.md §8.5)."""
        return registry.derived_input_names(vars(self))

    @property
    def input_names(self) -> list[str]:
        """The inputs of the scene's FMU, in value-reference order: the vectors (3
        components each: tau_body, tau_world, f_body, f_world, f_<point>, a_pivot), then
        each rotor's motor torque u_<name> (a scalar, N·m) or, in speed mode, its rate and
        its derivative (docs/theory.md §8.5)."""
        return registry.input_names(self)


def list_scenes() -> list[str]:
    """Names of the scenes shipped in modelsrc/scenes."""
    return shipped_names(SCENE_DIR)


def scene_path(name_or_path: str | Path) -> Path:
    """Resolve a scene name (shipped scene) or a path to a .toml file (modelsrc.shipped_files)."""
    return shipped_or_toml(name_or_path, SCENE_DIR, "scene")


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


def _read_stage(stage: ReadStage, ctx: SceneRead) -> None:
    """Run the features' readers of `stage`; their fields join ctx.fields."""
    for reader in registry.readers(stage):
        ctx.fields.update(reader.read(ctx))


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
    kw: dict[str, Any] = {}
    ctx = SceneRead(rd, features, kw)
    _read_stage(ReadStage.RULES, ctx)  # the features' rules before the others' fields
    if "mass" in body:
        kw["mass"] = rd.number("body.mass", body["mass"], positive=True)
    else:
        for feat in registry.NEEDS_MASS:
            if feat in features:
                raise rd.fail("body.mass", f"required when features.{feat} is true (kg, > 0)")
    _read_stage(ReadStage.MASS, ctx)

    kw["inertia"], principal, kw["pivot_inertia"] = read_inertia(
        rd, body, features, kw.get("mass", 1.0), kw.get("r_cm")
    )
    _read_stage(ReadStage.INERTIA, ctx)

    init = rd.section("initial", registry.start_keys(data))
    if "w_body" not in init:
        raise rd.fail("initial.w_body", "required: initial angular velocity, 3 numbers (rad/s, body frame)")
    w0 = rd.vector("initial.w_body", init["w_body"], 3)
    if "q" in init and "euler_zxz" in init:
        raise rd.fail("initial", "give at most one of 'q' and 'euler_zxz'")
    if "euler_zxz" in init:
        angles = rd.vector("initial.euler_zxz", init["euler_zxz"], 3)
        unit_mistakes.start_angles(f"scene file {rd.path}: field 'initial.euler_zxz'", [float(a) for a in angles])
        q0 = quat_from_euler_zxz(*angles)
    else:
        q0 = rd.vector("initial.q", init.get("q", [1.0, 0.0, 0.0, 0.0]), 4)
        nq = float(np.linalg.norm(q0))
        if abs(nq - 1.0) > QUAT_NORM_TOL:
            raise rd.fail(
                "initial.q", f"must be a unit quaternion (|q| within {QUAT_NORM_TOL} of 1), got |q| = {nq:.9g}"
            )
        q0 = q0 / nq
    ctx.initial = init
    _read_stage(ReadStage.START, ctx)

    inputs_sec = rd.section("inputs", registry.file_inputs(kw))
    inputs: dict[str, InputSpec] = {}
    for var, val in inputs_sec.items():
        for feature in registry.FEATURE_UNITS:
            if feature.check_input is not None:
                feature.check_input(rd, var, val, kw)
        owner = next((f for f, v in INPUT_OF_FEATURE.items() if v == var), None)
        if owner is not None and owner not in features:
            raise rd.fail(f"inputs.{var}", f"given but features.{owner} is not true")
        check_table_rows(rd, f"inputs.{var}", val)  # before each row is checked
        inputs[var] = parse_input(f"inputs.{var}", val, rd.vector, rd.number, rd.fail, input_width(var))
    inputs = registry.derived_inputs(inputs, kw)
    _read_stage(ReadStage.INPUTS, ctx)

    default_outs = [o for o in BODY_OUTPUTS]
    default_outs += [o.name for o in registry.OUTPUT_DECLARATIONS if o.in_default(kw)]
    default_outs = [o for o in default_outs if o not in OUTPUT_NEEDS or features & OUTPUT_NEEDS[o]]
    outs = data.get("outputs", default_outs)
    if not isinstance(outs, list) or any(o not in OUTPUTS for o in outs):
        raise rd.fail("outputs", f"must be a list drawn from {', '.join(OUTPUTS)}, got {outs!r}")
    outputs = tuple(o for o in OUTPUTS if o in set(outs) | set(STATE_OUTPUTS))
    ctx.outputs = outputs
    _read_stage(ReadStage.OUTPUTS, ctx)
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
    refusals = registry.refused_methods(features, kw)
    for refused, _ in refusals:
        allowed = [m for m in allowed if m not in refused]
    methods = exp.get("methods", allowed)
    if not isinstance(methods, list) or not methods or any(m not in allowed for m in methods):
        why = "splitting and exact_free need principal axes about the rotation point"
        why += "".join(f"; {reason}" for _, reason in refusals)
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
