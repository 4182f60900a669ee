"""The inputs of one run, decided once before it starts: held values, mode, closed loop and node values.

Inputs (modelsrc.scene_inputs), mode `inputs=`:
- "continuous" (default): the physical input. Tables switch on communication points, so
  they are set once per step; an input that varies inside a step (a harmonic) is also
  given to the FMU at every internal node time through FMI 3.0 intermediate update (the
  instance is created with a callback and those inputs as requiredIntermediateVariables),
  so the result is the method's, not the hold's (docs/fmi_layer.md, Inputs inside a step).
- "hold": every input held over a step at its mean there (zero-order hold, as most
  importers do), for comparison with them: a first-order error in the step for a harmonic.
A start value given for an input component (`start_values={"a_pivot[3]": 0}`, `--set`)
replaces the scene's schedule for that component: it is constant for the whole run.
A closed loop (`input_fn(t, outputs)`) replaces the schedules: its values are held over
each step, the input components given a start value still override them.

`InputPlan.of` reads all of this from the scene once per run; the driver's loop
(fmu.drive.run) and the sweeps' workers (fmu.sweep.worker) read the run's inputs from the
plan, not from the scene.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from modelsrc.errors import ModelInputError
from modelsrc.scene import Scene
from modelsrc.scene_inputs import Harmonic, component_names, input_component

InputFunction = Callable[[float, Mapping[str, float]], Mapping[str, float]]
INPUT_MODES = ("continuous", "hold")
# Sets input values by name before a step (FmuInstance.set).
InputSetter = Callable[[Mapping[str, float]], None]
# Sets the inputs of the step [t0, t1] (s) given the outputs at t0 (a row in FMU order).
StepInputs = Callable[[float, float, np.ndarray], None]


def input_mode(inputs: str) -> str:
    """`inputs` checked: one of INPUT_MODES (ModelInputError naming what is allowed)."""
    if inputs not in INPUT_MODES:
        raise ModelInputError(f"inputs must be one of {', '.join(INPUT_MODES)}, got {inputs!r}")
    return inputs


def check_input_hold(scene: Scene, start_values: Mapping[str, float] | None = None) -> None:
    """ModelInputError when holding the inputs over a step would change nothing: no input
    of the scene (after the constants of `start_values`) changes inside a communication
    step, being constant or a table (whose rows switch on communication points, which the
    run adds: `communication_points`), so --input-hold / inputs="hold" would be silently
    ignored. Only a harmonic (Scene.inputs_varying_in_step) is held otherwise than given."""
    held = scene.with_inputs_held(dict(start_values or {}))
    if not held.inputs_varying_in_step:
        kinds = "a table or constant" if held.switch_times() else "constant in time"
        raise ModelInputError(
            f'--input-hold (inputs="hold"): every input of scene {scene.name} is {kinds}'
            + (" (with the values set for this run)" if start_values else "")
            + ", and a table's rows switch on communication points, so holding the inputs over a step would "
            "change nothing; only a harmonic input changes inside a step: leave it out"
        )


def node_input_names(scene: Scene, inputs: str = "continuous") -> list[str]:
    """The input components a driver with `inputs` mode gives the FMU at its internal
    nodes: those of the scene's inputs that vary inside a step, in "continuous" mode."""
    if input_mode(inputs) == "hold":
        return []
    return [c for b in scene.inputs_varying_in_step for c in component_names(b)]


def node_values(scene: Scene, names: Sequence[str]) -> Callable[[float], list[float]]:
    """t (s) -> the values of the input components `names` ('a_pivot[3]') at t: the
    physical input (Scene.input_at), for the intermediate-update callback."""
    comps = [(b, int(k[:-1]) - 1 if k else 0) for b, _, k in (n.partition("[") for n in names)]
    specs = [s for b, _ in comps if isinstance(s := scene.inputs.get(b), Harmonic)]
    if len(specs) == len(comps):
        # the callback runs at every node of every internal step: plain floats and math.cos
        # (numpy's per-call overhead would triple its cost), offset + A cos(ω t + φ)
        terms = [(float(s.offset[k]), float(s.amplitude[k]), s.omega, s.phase) for s, (_, k) in zip(specs, comps)]
        cos = math.cos
        return lambda t: [c + a * cos(w * t + ph) for c, a, w, ph in terms]
    bases = list(dict.fromkeys(b for b, _ in comps))

    def values(t: float) -> list[float]:
        u = {b: scene.input_at(b, t) for b in bases}
        return [float(u[b][k]) for b, k in comps]

    return values


def scene_input(scene: Scene, name: str, t0: float, t1: float) -> np.ndarray:
    """Value of a scene's input `name` held over the communication step [t0, t1] (s): its
    mean there (a table's row in force at t0; modelsrc.scene_inputs)."""
    return scene.input_mean(name, t0, t1)


def communication_points(scene: Scene, stop_time: float, step: float) -> np.ndarray:
    """Communication points: the regular grid plus the switching times of input tables."""
    n = round(stop_time / step)
    if abs(n * step - stop_time) <= 1e-9 * stop_time:
        regular = np.arange(n + 1) * step
    else:
        regular = np.append(np.arange(0.0, stop_time, step), stop_time)
    switches = [t for t in scene.switch_times() if 0 < t < stop_time]
    pts = np.unique(np.concatenate([regular, np.asarray(switches, dtype=float)]))
    keep = np.concatenate([[True], np.diff(pts) > 1e-12 * max(1.0, stop_time)])
    return pts[keep]


@dataclass(frozen=True)
class InputPlan:
    """The inputs of one run, built once (`InputPlan.of`) before its first step.

    scene: the scene with every input component given a start value held at it for the
    whole run (Scene.with_inputs_held: its schedule replaced); mode: "continuous" or
    "hold"; input_fn: the closed loop's (t, outputs) -> {input name: value}, or None for
    the scene's schedules; held: the input components given a start value (name ->
    value), which override input_fn's values; node_inputs: the input components the FMU is
    given at its internal node times (intermediate update): those that vary inside a step,
    in "continuous" mode without input_fn; components: each scheduled input of the scene
    with its FMU variable names, in the order they are set.
    """

    scene: Scene
    mode: str
    input_fn: InputFunction | None
    held: Mapping[str, float]
    node_inputs: tuple[str, ...]
    components: tuple[tuple[str, tuple[str, ...]], ...]

    @classmethod
    def of(
        cls,
        scene: Scene,
        start_values: Mapping[str, float] | None = None,
        inputs: str = "continuous",
        input_fn: InputFunction | None = None,
    ) -> InputPlan:
        """The plan of a run of `scene` with these start values, input mode `inputs`
        (INPUT_MODES; ModelInputError otherwise) and closed loop `input_fn`."""
        mode = input_mode(inputs)
        values = dict(start_values or {})
        scene.refuse_derived_inputs(values, "start value")  # the plan would replace it (issue 39.5)
        held_scene = scene.with_inputs_held(values)  # a value given for an input replaces its schedule
        names = scene.input_names
        held = {n: float(v) for n, v in values.items() if input_component(n, names) is not None}
        nodes = tuple(node_input_names(held_scene, mode)) if input_fn is None else ()
        components = tuple((b, tuple(component_names(b))) for b in held_scene.inputs)
        return cls(held_scene, mode, input_fn, held, nodes, components)

    def communication_points(self, stop_time: float, step: float) -> np.ndarray:
        """The run's communication points (s): the regular grid of `step` up to `stop_time`
        plus the switching times of the input tables (`communication_points`)."""
        return communication_points(self.scene, stop_time, step)

    def node_values(self, names: Sequence[str]) -> Callable[[float], list[float]]:
        """t (s) -> the values of the input components `names` at t, for the
        intermediate-update callback (module function `node_values` on the plan's scene)."""
        return node_values(self.scene, names)

    def step_inputs(self, set_values: InputSetter, out_names: Sequence[str]) -> StepInputs:
        """The function the loop calls before the step [t0, t1] (s) with the outputs at t0
        (a row in the order of `out_names`): it sets the step's inputs through `set_values`
        (closed loop: input_fn's values with `held` over them; else every scheduled input at
        t0 when continuous, its mean over [t0, t1] when held)."""
        if self.input_fn is not None:
            fn, held = self.input_fn, self.held

            def closed_loop(t0: float, t1: float, outputs: np.ndarray) -> None:
                set_values({**fn(t0, dict(zip(out_names, outputs))), **held})

            return closed_loop
        scene, components, continuous = self.scene, self.components, self.mode == "continuous"

        def scheduled(t0: float, t1: float, outputs: np.ndarray) -> None:
            u: dict[str, float] = {}
            for base, names in components:
                val = scene.input_at(base, t0) if continuous else scene.input_mean(base, t0, t1)
                u.update(zip(names, (float(x) for x in val)))
            set_values(u)

        return scheduled
