"""What a validated scene holds (`SceneData`): the body, the features it uses, its start state, inputs and experiment.

`scene.load_scene` reads a scene file into a `scene.Scene`, which adds to this data what
follows from the features (torque-free, conserving energy, its inputs: modelsrc.registry).
The data sits below the features so that the model under construction
(`assembly.Assembly`) and every feature can read it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .features.free_motion.scene_file import ForcePoint
from .features.rotors.scene_file import Rotor
from .methods import DEFAULT_TOLERANCE
from .scene_inputs import InputSpec, input_at, input_mean, input_start, input_width, switch_times


@dataclass
class SceneData:
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
    method: the default one; rotors: name -> Rotor (modelsrc.features.rotors, the gyrostat
    of docs/theory.md §8), in value-reference order; orbit_rate: the rate n (rad/s) of the
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
        """True when the scene sets the flag `feature` of [features] (scene.FEATURES)."""
        return feature in self.features

    @property
    def fixed_step(self) -> float:
        """The internal step (s) of fixed stepping for this scene: h_max when the scene sets
        one, else a tenth of its communication step. The checks, the benchmark and the
        Exudyn references step with it (docs/theory.md §5.4)."""
        return fixed_step(self.h_max, self.step)

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

    def input_start(self, name: str) -> np.ndarray:
        """Value of input `name` at t = 0 (its start value); zeros without a schedule."""
        return input_start(self.inputs.get(name), input_width(name))

    def switch_times(self) -> list[float]:
        """Switching times (s) of the scene's input tables, sorted."""
        return sorted({t for spec in self.inputs.values() for t in switch_times(spec)})


def fixed_step(h_max: float, step: float) -> float:
    """A scene's internal step (s) of fixed stepping: h_max (s) when set (> 0), else a
    tenth of the communication step `step` (s) (Scene.fixed_step)."""
    return h_max if h_max > 0 else step / 10
