"""The feature descriptor: what one capability declares so that the scene reader, the scene and the model find it.

A capability (the rotors, the orbit, friction ...) is one unit of ``modelsrc/features/``:
a module, or a folder whose ``feature.py`` holds its descriptor, defining
``FEATURE = Feature(...)``. ``modelsrc.registry`` collects the units, and everything that
depends on which features a scene uses loops over them (docs/features.md):

* the scene file: the flags of ``[features]`` it owns, its tables and their keys, its
  ``[initial]`` and ``[inputs]`` keys, its readers (each at a `ReadStage` of
  ``scene.load_scene``), the methods it refuses and why;
* the scene: whether it puts a torque on the body, does work, moves the reference point,
  keeps the exact free flow, and its inputs in value-reference order;
* the model: its builders for each value-reference `Phase` (states, inputs, parameters),
  what it adds when the inertia is final, the angular acceleration where it replaces
  Euler's equations, and its contributions: the energy and angular momentum it carries
  relative to the body (summed by the body, `Assembly.internal_energy`,
  `Assembly.internal_momentum`), its outputs and its states' nominals.

Ranks order a feature's hooks among those of the other features where the order is part
of the FMU's interface (value references) or of the messages (which error comes first);
docs/features.md lists the ranks taken.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

import casadi as ca

from .assembly import Assembly
from .scene_data import SceneData
from .scene_reader import SceneReader
from .variables import Variable


class Phase(IntEnum):
    """The value-reference blocks the builders fill, in order (docs/theory.md §6): the body's
    q, w_body come first among the states, its inertia first among the parameters."""

    STATES = 1
    INPUTS = 2
    PARAMETERS = 3


class ReadStage(IntEnum):
    """When in ``scene.load_scene`` a feature's reader runs: after which part of the body."""

    RULES = 1  # after [features] and [body]: which features go together, the features' own tables
    MASS = 2  # after body.mass: what the inertia depends on ([gravity] r_cm)
    INERTIA = 3  # after the inertia
    START = 4  # after [initial] w_body and q
    INPUTS = 5  # after [inputs]
    OUTPUTS = 6  # after the outputs list


@dataclass
class SceneRead:
    """What a reader sees: the file's reader `rd` (errors name file and field), the
    features set, the Scene fields read so far, the [initial] table (empty before
    ReadStage.START) and the outputs (empty before ReadStage.OUTPUTS)."""

    rd: SceneReader
    features: frozenset[str]
    fields: dict[str, Any]
    initial: dict[str, Any] = field(default_factory=dict)
    outputs: tuple[str, ...] = ()


@dataclass(frozen=True)
class Reader:
    """A feature's part of reading a scene file: at `stage`, `rank` among the features'
    readers of that stage; returns Scene fields (name -> value)."""

    stage: ReadStage
    rank: int
    read: Callable[[SceneRead], Mapping[str, Any]]


@dataclass(frozen=True)
class Builder:
    """A feature's builder of one value-reference phase: adds its symbols, variables,
    terms and checks to the assembly (nothing when the scene does not use it); `rank`
    places it among the features' builders of the phase."""

    phase: Phase
    rank: int
    build: Callable[[Assembly], None]


@dataclass(frozen=True)
class Output:
    """An output a scene may request (scene.OUTPUTS): `rank` places it among the features'
    (after the body's), `needs` the flags of which it needs one (none: always allowed),
    `in_default` whether it is among the default outputs, given the Scene fields read."""

    name: str
    rank: int
    needs: frozenset[str] = frozenset()
    in_default: Callable[[Mapping[str, Any]], bool] = lambda fields: True


@dataclass(frozen=True)
class OutputValue:
    """A requested output's expression with its unit and description ("{}" takes the axis
    of a vector's entry), or its own variables (one per entry of the expression)."""

    expr: ca.SX
    unit: str | None
    description: str
    variables: tuple[Variable, ...] | None = None


@dataclass(frozen=True)
class OutputContext:
    """What the outputs are computed from besides the assembly: ω̇ (rad/s², body) and
    ω in the world frame, R ω (rad/s), as the body computed them."""

    omega_dot: ca.SX
    omega_world: ca.SX


# (name, expression, unit, description) of one scalar output
ScalarOutput = tuple[str, ca.SX, str | None, str]


@dataclass(frozen=True)
class Outputs:
    """Outputs a feature always has when the scene uses it, scalar by scalar: `rank` places
    them in y, before the requested outputs (rank < REQUESTED_RANK) or after them."""

    rank: int
    outputs: Callable[[Assembly, ca.SX], list[ScalarOutput]]


# The rank of the requested outputs (the body's and the features' `Output`s) in y.
REQUESTED_RANK = 50


@dataclass(frozen=True)
class AngularAcceleration:
    """ω̇ (rad/s², body) for the scenes where a feature replaces Euler's equations (the
    gyrostat, a prescribed rate): `replaces` tells for which scenes; `omega_dot` computes it
    once the inertia is final (and sets the rates of the feature's own states)."""

    replaces: Callable[[SceneData], bool]
    omega_dot: Callable[[Assembly], ca.SX]


def _none(*_: Any) -> bool:
    return False


@dataclass(frozen=True)
class FeatureDoc:
    """What a feature adds to an FMU's documentation (documentation/index.html) for a scene
    that uses it: `summary` (what it is in this scene, a phrase), `equations` ((equation,
    source) pairs, the source a section of docs/theory.md and a book), `conserved` (what it
    conserves while no other feature works on the body: the output and its section), and
    whether its equations replace Euler's (`replaces_euler`, §2.1)."""

    summary: str
    equations: tuple[tuple[str, str], ...] = ()
    conserved: tuple[str, ...] = ()
    replaces_euler: bool = False


def _no_doc(scene: SceneData) -> FeatureDoc | None:
    return None


@dataclass(frozen=True)
class Feature:
    """One capability and everything it declares (see the module's docstring).

    name: the unit's name; order: its place among the features (the flags of [features],
    the inputs a flag owns, the reasons of refused methods, the sums of energy and
    momentum follow it). Scene file: flags, tables (table -> its keys; None for a table
    of named tables the feature reads itself), start_keys (the [initial] keys it allows,
    given the parsed file), needs_mass (flags that need body.mass), readers,
    input_of_flag (flag -> the input it makes), file_inputs (the further [inputs] keys the
    fields read allow), check_input(rd, name, value, fields) (refuses an [inputs] value
    before it is parsed), derived_inputs(inputs, fields) (schedules derived from the given ones),
    derived_input_names(fields) (the inputs derived_inputs always re-derives: not settable by a
    run), excluded_methods with excluded_why (a clause of the refusal) when excludes_methods (features, fields).
    Scene: torque_flags, working_flags, motion_flags (flags that put a torque on the body,
    do work, move the reference point) and the predicates adds_torque, does_work,
    blocks_exact_flow (default: any of those flags set), input_names (its FMU inputs in
    value-reference order). Model: builders, finish (after the inertia is final),
    angular_acceleration, energy(a, ω, total) -> total + its kinetic energy relative to
    the body (J), momentum(a, total) -> total + its angular momentum relative to the body
    (N·m·s, body), outputs (requestable), requested (their values), always (outputs it
    always has), nominals(scene, out) (its states' nominal magnitudes, modelsrc.nominals).
    Documentation: doc(scene) (`FeatureDoc`: equations, conserved quantities; None where not used).
    """

    name: str
    order: int
    flags: tuple[str, ...] = ()
    tables: Mapping[str, frozenset[str] | None] = field(default_factory=dict)
    start_keys: Callable[[Mapping[str, Any]], frozenset[str]] = lambda data: frozenset()
    needs_mass: tuple[str, ...] = ()
    readers: tuple[Reader, ...] = ()
    input_of_flag: Mapping[str, str] = field(default_factory=dict)
    file_inputs: Callable[[Mapping[str, Any]], frozenset[str]] = lambda fields: frozenset()
    check_input: Callable[[SceneReader, str, Any, Mapping[str, Any]], None] | None = None
    derived_inputs: Callable[[dict[str, Any], Mapping[str, Any]], dict[str, Any]] | None = None
    derived_input_names: Callable[[Mapping[str, Any]], frozenset[str]] = lambda fields: frozenset()
    excluded_methods: tuple[str, ...] = ()
    excluded_why: str = ""
    excludes_methods: Callable[[frozenset[str], Mapping[str, Any]], bool] = _none
    torque_flags: frozenset[str] = frozenset()
    adds_torque: Callable[[SceneData], bool] | None = None
    working_flags: frozenset[str] = frozenset()
    does_work: Callable[[SceneData], bool] | None = None
    motion_flags: frozenset[str] = frozenset()
    blocks_exact_flow: Callable[[SceneData], bool] = _none
    input_names: Callable[[SceneData], list[str]] = lambda scene: []
    builders: tuple[Builder, ...] = ()
    finish: Callable[[Assembly], None] | None = None
    angular_acceleration: AngularAcceleration | None = None
    energy: Callable[[Assembly, ca.SX, ca.SX], ca.SX] | None = None
    momentum: Callable[[Assembly, ca.SX], ca.SX] | None = None
    outputs: tuple[Output, ...] = ()
    requested: Callable[[Assembly, OutputContext], dict[str, OutputValue]] | None = None
    always: Outputs | None = None
    nominals: Callable[[SceneData, dict[str, float]], None] | None = None
    doc: Callable[[SceneData], FeatureDoc | None] = _no_doc

    def torque_on(self, scene: SceneData) -> bool:
        """The feature puts a torque on the body about the point it turns about."""
        return self.adds_torque(scene) if self.adds_torque else bool(scene.features & self.torque_flags)

    def works_on(self, scene: SceneData) -> bool:
        """The feature's forces or torques do work that is not the change of a potential."""
        return self.does_work(scene) if self.does_work else bool(scene.features & self.working_flags)
