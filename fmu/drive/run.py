"""Co-simulation of a scene's FMU through fmpy (FMI 3.0 Co-Simulation): the driver's communication loop.

`run_fmu` instantiates a scene's FMU (fmu.drive.instance), steps it over the scene's
experiment, feeding the inputs (torques, forces, pivot acceleration) from the scene's
schedules or from a Python function as the run's `InputPlan` says (fmu.drive.inputs: built
once per run), and records every output; `simulate` is that loop on an instance that
already exists (the sweeps reuse one instance for many runs through fmi3Reset).
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from modelsrc.errors import ModelInputError
from modelsrc.methods import METHODS, error_controlled, method_by_value
from modelsrc.scene import Scene

from .arguments import bool_arg, callable_arg, fmu_arg, names_arg, scene_arg
from .inputs import InputFunction, InputPlan, StepInputs
from .instance import FmuInstance
from .logged_warnings import LoggedWarnings
from .start_values import check_start_values

# A run records every output at every communication point: 1e6 points of the ~30 outputs
# are 240 MB and ~20 s through fmpy. A longer run is refused before anything is allocated.
MAX_COMMUNICATION_POINTS = 1_000_000


@dataclass
class RunResult:
    """Outputs of one co-simulation: time (s) and one array per output variable name; `inputs`:
    one array per FMU input component, the value the FMU was given at the start of the step
    that starts at each time (at the end time: the schedule's value there in a continuous run,
    else the last step's)."""

    scene: Scene
    time: np.ndarray
    values: dict[str, np.ndarray]
    wall_time: float
    n_steps: int
    inputs: dict[str, np.ndarray] = field(default_factory=dict)

    def vector(self, base: str) -> np.ndarray:
        """Stack the components base[1], base[2], ... into an (n, k) array."""
        cols = []
        k = 1
        while f"{base}[{k}]" in self.values:
            cols.append(self.values[f"{base}[{k}]"])
            k += 1
        if not cols:
            if base in self.values:
                return self.values[base]
            raise KeyError(base)
        return np.column_stack(cols)


def run_length(stop_time: float, step: float) -> tuple[float, float]:
    """(stop_time, step) in s, checked: finite, > 0, the step at most the stop time, and at
    most MAX_COMMUNICATION_POINTS steps (ModelInputError saying what is allowed)."""
    for label, v in (("stop_time", stop_time), ("step", step)):
        number = isinstance(v, (int, float, np.number)) and not isinstance(v, bool)
        if not (number and np.isfinite(v) and v > 0):
            raise ModelInputError(f"{label} must be a finite number > 0, got {v if number else repr(v)}")
    if step > stop_time * (1 + 1e-12):  # it would be cut to one step of stop_time without a word
        raise ModelInputError(
            f"step {step:g} s is longer than the run (stop_time {stop_time:g} s): give a step of at most the stop time"
        )
    n = stop_time / step
    if not n <= MAX_COMMUNICATION_POINTS:
        raise ModelInputError(
            f"stop_time {stop_time:g} s with step {step:g} s makes {n:.3g} communication steps; a run records every "
            f"output at each, at most {MAX_COMMUNICATION_POINTS:,}: take a larger step or a shorter stop time"
        )
    return float(stop_time), float(step)


def experiment(scene: Scene, stop_time: float | None = None, step: float | None = None) -> tuple[float, float]:
    """(stop time, communication step) in s: the given values, else the scene's, checked
    by `run_length` (finite, > 0, not too many communication points); the scene's step, not
    given, is cut to a shorter stop time given (one step), a step given is not."""
    T = scene.stop_time if stop_time is None else stop_time
    if step is None and isinstance(T, (int, float)) and not isinstance(T, bool) and 0 < T < scene.step:
        return run_length(T, T)
    return run_length(T, scene.step if step is None else step)


def simulate(
    inst: FmuInstance,
    scene: Scene | str | Path,
    stop_time: float | None = None,
    step: float | None = None,
    start_values: Mapping[str, float] | None = None,
    input_fn: InputFunction | None = None,
    outputs: Sequence[str] | None = None,
    direct: bool = False,
    inputs: str = "continuous",
    raise_warnings: bool = True,
) -> RunResult:
    """Co-simulate on an instance that was just instantiated or reset (fmi3Reset): set
    the start values, initialise, step from t = 0 to stop_time (s) with communication
    step `step` (s). Arguments and result as `run_fmu`; this is its loop, shared with the
    sweeps (fmu.sweep.worker), which reuse one instance for many runs. direct: doStep and
    getFloat64 through `DirectCalls` instead of fmpy (the same calls, the same values).
    inputs "continuous" needs an instance created with node_inputs =
    `node_input_names(scene)` (ModelInputError otherwise). start_values are checked as
    run_fmu's, without its unit-mistake warnings (the sweeps' loop: their values were checked
    once); the warnings the FMU logs during the run are raised as run_fmu's (FmuWarning), or
    with raise_warnings False left in inst.warnings for the caller (a sweep's worker sends
    them to the client, which shows them once for the whole sweep: fmu.sweep.api)."""
    if not isinstance(inst, FmuInstance):
        raise ModelInputError(f"inst must be an FmuInstance (fmu.drive.instance), got {type(inst).__name__}")
    scene = scene_arg(scene)
    _check_scene_of(inst, scene)
    input_fn, outputs = callable_arg(input_fn, "input_fn"), names_arg(outputs, "outputs")
    direct, raise_warnings = bool_arg(direct, "direct"), bool_arg(raise_warnings, "raise_warnings")
    T, H = experiment(scene, stop_time, step)
    values = check_start_values(start_values, methods=inst.method_values, warn=False)
    plan = InputPlan.of(scene, values, inputs, input_fn)
    if not raise_warnings:
        return co_simulate(inst, plan, T, H, values, outputs, direct)
    with LoggedWarnings(inst):
        return co_simulate(inst, plan, T, H, values, outputs, direct)


def _check_scene_of(inst: FmuInstance, scene: Scene) -> None:
    """ModelInputError unless the FMU was built from a scene of this name (its modelName):
    the scene gives the run its experiment and input schedules, another scene's would drive
    the FMU's body with them."""
    built_from = inst.md.modelName
    if built_from != scene.name:
        raise ModelInputError(
            f"{inst.path} was built from scene {built_from!r}, not from the given scene {scene.name!r}; "
            "pass the scene it was built from"
        )


def co_simulate(
    inst: FmuInstance,
    plan: InputPlan,
    stop_time: float,
    step: float,
    start_values: Mapping[str, float] | None = None,
    outputs: Sequence[str] | None = None,
    direct: bool = False,
) -> RunResult:
    """`simulate` with the run's inputs already planned (`InputPlan.of`) and stop_time,
    step (s) already checked (`experiment`): the loop `run_fmu` and `simulate` share."""
    missing = sorted(set(plan.node_inputs) - set(inst.node_inputs))
    if missing:
        raise ModelInputError(
            f"continuous inputs need an instance that asks for {', '.join(missing)} inside a step: create it with "
            "FmuInstance(..., node_inputs=node_input_names(scene)), or run with inputs='hold'"
        )
    inst.node_values = plan.node_values(inst.node_inputs) if plan.node_inputs else None
    out_names = list(outputs) if outputs else [v.name for v in inst.md.modelVariables if v.causality == "output"]
    in_names = [v.name for v in inst.md.modelVariables if v.causality == "input"]
    out_vrs = inst.value_references(out_names)
    inst.set(dict(start_values or {}))
    inst.initialize(0.0, stop_time)
    grid = plan.communication_points(stop_time, step)
    rows = np.empty((len(grid), len(out_names)))
    if direct:
        calls = inst.direct_calls()
        step_fn, read_row = calls.step, calls.reader(out_vrs)
    else:
        step_fn = inst.step

        def read_row(dst: np.ndarray) -> None:
            dst[:] = inst.get_float64(out_vrs)

    in_rows = np.empty((len(grid), len(in_names)))
    t0 = _time.perf_counter()
    if direct and not in_names:
        calls.run(grid, out_vrs, rows)
    else:
        set_inputs = _recording(plan.step_inputs, inst, in_names, in_rows, out_names) if in_names else None
        _step_loop(grid, rows, step_fn, read_row, set_inputs)
    wall = _time.perf_counter() - t0
    if in_names and len(grid) > 1:
        _last_inputs(plan, in_names, in_rows, float(grid[-1]))
    return RunResult(
        scene=plan.scene,
        time=grid,
        values={n: rows[:, k] for k, n in enumerate(out_names)},
        wall_time=wall,
        n_steps=len(grid) - 1,
        inputs={n: in_rows[:, k] for k, n in enumerate(in_names)},
    )


def _last_inputs(plan: InputPlan, in_names: Sequence[str], in_rows: np.ndarray, t_end: float) -> None:
    """The inputs' row at the end time, which starts no step: the last step's values, and the
    schedule's value at the end for the scheduled inputs of a continuous run (no closed loop)."""
    in_rows[-1] = in_rows[-2]
    if plan.input_fn is None and plan.mode == "continuous":
        index = {n: k for k, n in enumerate(in_names)}
        for base, names in plan.components:
            for name, v in zip(names, plan.scene.input_at(base, t_end)):
                if name in index:
                    in_rows[-1, index[name]] = float(v)


def _recording(
    step_inputs: Callable[[Callable[[Mapping[str, float]], None], Sequence[str]], StepInputs],
    inst: FmuInstance,
    in_names: Sequence[str],
    in_rows: np.ndarray,
    out_names: Sequence[str],
) -> StepInputs:
    """The plan's step inputs (`InputPlan.step_inputs`) that also record, for every step, the
    value of each input component the FMU was given (its value at initialisation until a step
    sets it) into the row of in_rows of the step's start."""
    current = np.asarray(inst.get_float64(inst.value_references(list(in_names))), dtype=float)
    index = {n: k for k, n in enumerate(in_names)}
    in_rows[0] = current

    def set_values(u: Mapping[str, float]) -> None:
        inst.set(u)
        for name, v in u.items():
            if name in index:
                current[index[name]] = v

    fn = step_inputs(set_values, out_names)
    count = [0]

    def step(t0: float, t1: float, outputs: np.ndarray) -> None:
        fn(t0, t1, outputs)
        in_rows[count[0]] = current
        count[0] += 1

    return step


def _step_loop(
    grid: np.ndarray,
    rows: np.ndarray,
    step_fn: Callable[[float, float], None],
    read_row: Callable[[np.ndarray], None],
    set_inputs: StepInputs | None,
) -> None:
    """The communication loop of `co_simulate`: the outputs at grid[0] into rows[0], then
    for every step the inputs set (`set_inputs`, from the run's InputPlan; None when the
    FMU has no inputs), doStep from grid[i] to grid[i + 1] (s) and the outputs into rows[i + 1]."""
    read_row(rows[0])
    for i in range(len(grid) - 1):
        t = grid[i]
        if set_inputs is not None:
            set_inputs(t, grid[i + 1], rows[i])
        step_fn(t, grid[i + 1] - t)
        read_row(rows[i + 1])


def refuse_unused_tolerance(scene: Scene, values: Mapping[str, float]) -> None:
    """ModelInputError for a `tolerance` > 0 in `values` (start values) with a method that
    has no error estimate (modelsrc.methods.error_controlled: splitting, exact_free), the
    one in `values` or else the scene's: such a method always takes fixed steps
    (docs/user_guide.md §2.2), so the tolerance would have no effect."""
    tol = values.get("tolerance", 0.0)
    if not tol > 0:
        return
    method = method_by_value(int(values["method"])).name if "method" in values else scene.method
    if not error_controlled(method):
        controlled = ", ".join(m for m in METHODS if error_controlled(m))
        raise ModelInputError(
            f"tolerance = {tol:g}: method {method} has no error estimate and always takes fixed steps "
            f"(docs/user_guide.md §2.2), so a tolerance would have no effect; set h_max for its step, or choose a "
            f"method with error control ({controlled})"
        )


def run_fmu(
    fmu_path: str | Path,
    scene: Scene | str | Path,
    stop_time: float | None = None,
    step: float | None = None,
    start_values: Mapping[str, float] | None = None,
    input_fn: InputFunction | None = None,
    outputs: Sequence[str] | None = None,
    inputs: str = "continuous",
) -> RunResult:
    """Co-simulate the scene's FMU from t = 0 to stop_time with communication step `step`.

    fmu_path: the scene's .fmu (FMI 3.0); scene: the Scene it was built from (its
    experiment and input schedules), or its shipped name or .toml file; an FMU built from
    another scene is refused. Every argument is listed in docs/user_guide.md §4.1; a bad
    type or value is a ModelInputError naming it (fmu.drive.arguments). stop_time, step: s, finite, > 0 (default: the
    scene's [experiment]; at most MAX_COMMUNICATION_POINTS steps).
    start_values: name -> value set before initialisation (start state, parameters), a
    finite number or its text; `method` by name ('gauss4') or enumeration value, as
    `rbfmu run --set` (fmu.drive.start_values: a bad value is a ModelInputError naming it
    and what is allowed; a value almost surely in the wrong unit is warned about); a
    value for an input component ('f_thr_a[1]') holds it constant for the whole run,
    replacing the scene's schedule for it.
    input_fn(t, outputs) -> {input name: value}: called at every communication point with
    the latest outputs (closed loop; held over the step); without it, the scene's input
    schedules are used: inputs "continuous" (default) gives the FMU the physical input,
    inside a step too (FMI 3.0 intermediate update); "hold" holds each over a step at its
    mean there (`scene_input`), as an importer without intermediate update does.
    Returns every output (or the names in `outputs`) at every communication point.
    Each warning the FMU logs during the run (a tolerance it cannot resolve, ...) is raised
    as an FmuWarning (fmu.drive.logged_warnings: each distinct message once, with its count).
    The run's inputs are planned once (fmu.drive.inputs.InputPlan) and drive both the
    instance's node inputs and the loop.
    """
    fmu_path, scene = fmu_arg(fmu_path), scene_arg(scene)
    input_fn, outputs = callable_arg(input_fn, "input_fn"), names_arg(outputs, "outputs")
    values = check_start_values(start_values)
    T, H = experiment(scene, stop_time, step)
    plan = InputPlan.of(scene, values, inputs, input_fn)
    with FmuInstance(fmu_path, node_inputs=plan.node_inputs) as inst:
        _check_scene_of(inst, scene)
        if "method" in values:  # among the methods compiled into this FMU
            check_start_values({"method": values["method"]}, methods=inst.method_values, warn=False)
        refuse_unused_tolerance(scene, values)
        with LoggedWarnings(inst):
            return co_simulate(inst, plan, T, H, values, outputs)
