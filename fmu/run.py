"""Co-simulation of a scene's FMU through fmpy (FMI 3.0 Co-Simulation).

`FmuInstance` wraps fmpy's FMU3Slave: names instead of value references, the FMU's
log messages collected and attached to any error. `run_fmu` steps it over a scene's
experiment, feeding the inputs (torques, forces, pivot acceleration) from the scene's
schedules or from a Python function, and records every output; `simulate` is that loop
on an instance that already exists (the sweeps reuse one instance for many runs through
fmi3Reset).

Inputs (modelsrc.scene_inputs), `inputs=`:
- "continuous" (default): the physical input. Tables switch on communication points, so
  they are set once per step; an input that varies inside a step (a harmonic) is also
  given to the FMU at every internal node time through FMI 3.0 intermediate update (the
  instance is created with a callback and those inputs as requiredIntermediateVariables),
  so the result is the method's, not the hold's (docs/fmi_layer.md, Inputs inside a step).
- "hold": every input held over a step at its mean there (zero-order hold, as most
  importers do), for comparison with them: a first-order error in the step for a harmonic.
A start value given for an input component (`start_values={"a_pivot[3]": 0}`, `--set`)
replaces the scene's schedule for that component: it is constant for the whole run.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import time as _time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave, fmi3LogMessageCallback

from modelsrc.errors import ModelInputError, unknown_variable
from modelsrc.scene import Scene
from modelsrc.scene_inputs import Harmonic, component_names

InputFunction = Callable[[float, Mapping[str, float]], Mapping[str, float]]
INPUT_MODES = ("continuous", "hold")
# A run records every output at every communication point: 1e6 points of the ~30 outputs
# are 240 MB and ~20 s through fmpy. A longer run is refused before anything is allocated.
MAX_COMMUNICATION_POINTS = 1_000_000


class FmuError(RuntimeError):
    """An FMI call failed; the message carries the FMU's own log messages."""


def settable_variables(md) -> list[str]:
    """The names in an FMU's modelDescription (fmpy's) that a user may set before a run, in
    value-reference order: parameters, inputs and the states' start values (outputs with
    initial="exact"); the same rule as the sweeps' (fmu.sweep.spec.Variables)."""
    return [
        v.name
        for v in md.modelVariables
        if v.causality in ("parameter", "input") or (v.causality == "output" and v.initial == "exact")
    ]


class FmuInstance:
    """One instance of an FMI 3.0 Co-Simulation FMU, driven through fmpy.

    Use as a context manager; `close()` terminates and frees the instance and removes
    the extracted archive (extracted into `unzipdir` if given, else a temporary directory).
    node_inputs: input names ('a_pivot[3]') the FMU asks for at its internal node times
    (FMI 3.0 intermediate update); at each node the callback sets them to
    `node_values(t)` (a sequence in the order of node_inputs), or sets nothing (the
    inputs are then held) while `node_values` is None.
    """

    def __init__(
        self,
        fmu_path: str | Path,
        instance_name: str = "rb",
        unzipdir: str | Path | None = None,
        node_inputs: Sequence[str] = (),
    ):
        self.path = Path(fmu_path)
        self.md = read_model_description(str(self.path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.settable = settable_variables(self.md)
        self._unzipdir = extract(str(self.path), unzipdir=None if unzipdir is None else str(unzipdir))
        self.messages: list[str] = []

        def _log(env, status, category, message):  # keep FMU messages for error reports
            self.messages.append(message.decode("utf-8", "replace"))

        self._log_cb = fmi3LogMessageCallback(_log)
        self.fmu = FMU3Slave(
            guid=self.md.guid,
            unzipDirectory=self._unzipdir,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=instance_name,
        )
        self.node_inputs = tuple(node_inputs)
        self.node_values: Callable[[float], Sequence[float]] | None = None
        self.node_error: BaseException | None = None
        extra = self._node_callback() if self.node_inputs else {}
        self._call(self.fmu.instantiate, "instantiate", logMessage=_log, **extra)
        self.time = 0.0

    def _node_callback(self) -> dict[str, object]:
        """instantiate's arguments for intermediate update of `node_inputs`: a callback that
        sets them through a raw fmi3SetFloat64 (preset argument types, one preallocated
        array: the callback runs at every node of every internal step)."""
        vrs = self.value_references(self.node_inputs)
        k = len(vrs)
        c_vrs, buf = (ctypes.c_uint32 * k)(*vrs), (ctypes.c_double * k)()
        raw = self.fmu.dll.fmi3SetFloat64
        raw.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint32), ctypes.c_size_t,
                        ctypes.POINTER(ctypes.c_double), ctypes.c_size_t]  # fmt: skip
        raw.restype = ctypes.c_int
        fmu = self.fmu

        def update(env, t, set_requested, get_allowed, finished, can_return, early, early_time):
            values = self.node_values
            if values is None or self.node_error is not None:
                return
            try:  # an exception cannot cross the C callback: kept, raised after the doStep
                buf[:] = values(t)
                if raw(fmu.component, c_vrs, k, buf, k) > FMI3_WARNING:
                    raise FmuError(f"setting {', '.join(self.node_inputs)} at the node t = {t} failed")
            except BaseException as exc:  # re-raised by step() after the doStep
                self.node_error = exc

        return {"intermediateUpdate": update, "requiredIntermediateVariables": vrs}

    def raise_node_error(self) -> None:
        """Raise (once) an error the intermediate-update callback caught during a doStep."""
        exc, self.node_error = self.node_error, None
        if exc is not None:
            raise FmuError(f"the inputs' callback failed inside a doStep: {exc}") from exc

    def _call(self, fn, what: str | Callable[[], str], *args, **kwargs):
        # `what` may be a callable, formatted only on failure: per-step calls (doStep) in
        # timed loops then cost no string formatting
        n = len(self.messages)
        try:
            return fn(*args, **kwargs)
        except FMICallException as exc:
            raise self.failure(what if isinstance(what, str) else what(), n) from exc
        except Exception as exc:  # fmpy raises plain Exception for a NULL instance
            log = "; ".join(self.messages[n:]) or str(exc)
            raise FmuError(f"{what if isinstance(what, str) else what()} failed: {log}") from exc

    def value_references(self, names: Sequence[str]) -> list[int]:
        """Value references of variables by name; ModelInputError naming unknown ones."""
        unknown = [n for n in names if n not in self.vr]
        if unknown:  # the names a user reads (the derivatives der(...) are the FMU's own)
            readable = [n for n in self.vr if not n.startswith("der(")]
            raise unknown_variable(unknown[0], readable, listed="variables")
        return [self.vr[n] for n in names]

    _vrs = value_references  # short internal name

    @property
    def method_values(self) -> dict[str, int]:
        """Integrator name -> value of the ``method`` enumeration, read from the
        modelDescription (the methods compiled into this FMU)."""
        mvar = self.variables.get("method")
        if mvar is None or mvar.declaredType is None:
            return {}
        return {item.name: int(item.value) for item in mvar.declaredType.items}

    def get_float64(self, vrs: Sequence[int]) -> list[float]:
        """Float64 values by value reference (the fast path of `get`: no name lookup)."""
        return self._call(self.fmu.getFloat64, "getFloat64", vrs)

    def set_float64(self, vrs: Sequence[int], values: Sequence[float]) -> None:
        """Set Float64 values by value reference (the fast path of `set`)."""
        self._call(self.fmu.setFloat64, "setFloat64", vrs, values)

    def step(self, t: float, h: float) -> None:
        """doStep(t, h) from the communication point t (s); sets `time` to t + h."""
        self._call(self.fmu.doStep, lambda: f"doStep(t={t}, h={h})", t, h)
        self.raise_node_error()
        self.time = t + h

    def reset(self) -> None:
        """fmi3Reset: back to the state after instantiation (start values restored)."""
        self._call(self.fmu.reset, "reset")
        self.time = 0.0

    def c_function(self, name: str):
        """The FMU library's C function `name` (ctypes), for loops that time the FMU's own
        work without fmpy's Python layer (fmu/benchmark.py)."""
        return getattr(self.fmu.dll, name)

    @property
    def c_instance(self):
        """The fmi3Instance pointer to pass to `c_function`s."""
        return self.fmu.component

    def direct_calls(self) -> DirectCalls:
        """fmi3DoStep and fmi3GetFloat64 called through ctypes without fmpy's per-call
        wrapper (a few µs per call, more than the FMU's own step at small steps), with the
        same FmuError reports as `step` and `get_float64`: for loops of many runs (sweeps)."""
        return DirectCalls(self)

    def failure(self, what: str, first_message: int) -> FmuError:
        """The FmuError of a failed call: `what` and the FMU's messages logged since the
        message number `first_message` (the length of `messages` before the call)."""
        log = "; ".join(self.messages[first_message:]) or "(the FMU logged nothing)"
        return FmuError(f"{what} failed: {log}")

    def set(self, values: Mapping[str, float]) -> None:
        """Set variables by name (start values, parameters, inputs); Float64 variables
        through setFloat64, the `method` enumeration through setInt64."""
        if not values:
            return
        for name in values:
            if name not in self.settable:
                raise unknown_variable(name, self.settable, known=self.vr)
        floats = {n: v for n, v in values.items() if self.variables[n].type == "Float64"}
        ints = {n: v for n, v in values.items() if self.variables[n].type != "Float64"}
        if floats:
            self._call(
                self.fmu.setFloat64,
                f"setting {', '.join(floats)}",
                self._vrs(list(floats)),
                [float(v) for v in floats.values()],
            )
        if ints:
            bad = [n for n, v in ints.items() if float(v) != int(v)]
            if bad:
                raise ModelInputError(f"{bad[0]} takes an integer (enumeration value), got {ints[bad[0]]}")
            self._call(
                self.fmu.setInt64, f"setting {', '.join(ints)}", self._vrs(list(ints)), [int(v) for v in ints.values()]
            )

    def get(self, names: Sequence[str]) -> np.ndarray:
        """Get variables by name (Float64, or the `method` enumeration as a number)."""
        out = np.empty(len(names))
        for k, n in enumerate(names):
            vr = self._vrs([n])
            fn = self.fmu.getFloat64 if self.variables[n].type == "Float64" else self.fmu.getInt64
            out[k] = self._call(fn, f"getting {n}", vr)[0]
        return out

    def initialize(self, start_time: float = 0.0, stop_time: float | None = None) -> None:
        """Enter and exit initialisation mode (start values must be set before)."""
        self._call(
            self.fmu.enterInitializationMode, "enterInitializationMode", startTime=start_time, stopTime=stop_time
        )
        self._call(self.fmu.exitInitializationMode, "exitInitializationMode")
        self.time = start_time

    def do_step(self, h: float) -> None:
        """Advance by h seconds from the current time."""
        self.step(self.time, h)

    def close(self) -> None:
        """Terminate (if the state allows), free the instance and the library, remove the
        extracted files. Errors of terminate (e.g. after a failed initialisation) are
        expected here and ignored: the instance is freed either way."""
        import shutil

        with contextlib.suppress(FMICallException):
            self.fmu.terminate()
        self.fmu.freeInstance()  # fmpy >= 0.3.32 unloads the library here; unloading twice is a use-after-free
        shutil.rmtree(self._unzipdir, ignore_errors=True)

    def __enter__(self) -> FmuInstance:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


FMI3_WARNING = 1  # fmi3Status: OK 0, Warning 1, Discard 2, Error 3, Fatal 4; fmpy fails above Warning


class DirectCalls:
    """fmi3DoStep and fmi3GetFloat64 of one instance through ctypes with preset argument
    types: the calls of `FmuInstance.step` and `get_float64`, without fmpy's wrapper."""

    def __init__(self, inst: FmuInstance):
        self.inst = inst
        self._comp = inst.c_instance
        b = ctypes.c_bool
        self._do = inst.c_function("fmi3DoStep")
        self._do.argtypes = [
            ctypes.c_void_p,
            ctypes.c_double,
            ctypes.c_double,
            b,
            ctypes.POINTER(b),
            ctypes.POINTER(b),
            ctypes.POINTER(b),
            ctypes.POINTER(ctypes.c_double),
        ]
        self._do.restype = ctypes.c_int
        self._flags = (b(), b(), b(), ctypes.c_double())  # outputs of fmi3DoStep, unused here
        self._refs = [ctypes.byref(f) for f in self._flags]
        self._get = inst.c_function("fmi3GetFloat64")
        vr_p = ctypes.POINTER(ctypes.c_uint32)
        self._get.argtypes = [ctypes.c_void_p, vr_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_size_t]
        self._get.restype = ctypes.c_int

    def step(self, t: float, h: float) -> None:
        """doStep(t, h) from the communication point t (s), as `FmuInstance.step`."""
        n = len(self.inst.messages)
        if self._do(self._comp, t, h, True, *self._refs) > FMI3_WARNING:
            raise self.inst.failure(f"doStep(t={t}, h={h})", n)
        self.inst.raise_node_error()
        self.inst.time = t + h

    def reader(self, vrs: Sequence[int]) -> Callable[[np.ndarray], None]:
        """A function that writes the Float64 values of `vrs` into a contiguous float64
        array of len(vrs) (e.g. one row of a C-ordered table)."""
        k = len(vrs)
        c_vrs = (ctypes.c_uint32 * k)(*vrs)
        get, comp, inst = self._get, self._comp, self.inst

        def read(dst: np.ndarray) -> None:
            n = len(inst.messages)
            if get(comp, c_vrs, k, dst.ctypes.data, k) > FMI3_WARNING:
                raise inst.failure("getFloat64", n)

        return read

    def run(self, grid: np.ndarray, vrs: Sequence[int], rows: np.ndarray) -> None:
        """Read `vrs` into rows[0], then for every i doStep from grid[i] to grid[i + 1] (s)
        and read them into rows[i + 1] (rows: C-ordered float64, len(grid) × len(vrs)): the
        loop of `simulate` without inputs, its per-step Python work cut to the two calls."""
        if rows.shape != (len(grid), len(vrs)) or rows.dtype != np.float64 or not rows.flags.c_contiguous:
            raise ValueError("rows must be a C-ordered float64 array of len(grid) x len(vrs)")
        k = len(vrs)
        c_vrs = (ctypes.c_uint32 * k)(*vrs)
        do, get, comp, messages = self._do, self._get, self._comp, self.inst.messages
        r1, r2, r3, r4 = self._refs
        address, stride = rows.ctypes.data, rows.strides[0]
        ts = [float(x) for x in grid]
        n = len(messages)
        if get(comp, c_vrs, k, address, k) > FMI3_WARNING:
            raise self.inst.failure("getFloat64", n)
        for i in range(len(ts) - 1):
            t, h = ts[i], ts[i + 1] - ts[i]
            n = len(messages)
            if do(comp, t, h, True, r1, r2, r3, r4) > FMI3_WARNING:
                raise self.inst.failure(f"doStep(t={t}, h={h})", n)
            if get(comp, c_vrs, k, address + (i + 1) * stride, k) > FMI3_WARNING:
                raise self.inst.failure("getFloat64", n)
        self.inst.time = ts[-1]


@dataclass
class RunResult:
    """Outputs of one co-simulation: time (s) and one array per output variable name."""

    scene: Scene
    time: np.ndarray
    values: dict[str, np.ndarray]
    wall_time: float
    n_steps: int

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


def input_mode(inputs: str) -> str:
    """`inputs` checked: one of INPUT_MODES (ModelInputError naming what is allowed)."""
    if inputs not in INPUT_MODES:
        raise ModelInputError(f"inputs must be one of {', '.join(INPUT_MODES)}, got {inputs!r}")
    return inputs


def check_input_hold(scene: Scene, start_values: Mapping[str, float] | None = None) -> None:
    """ModelInputError when holding the inputs over a step would change nothing: every
    input of the scene (after the constants of `start_values`) is constant in time, so
    --input-hold / inputs="hold" would be silently ignored."""
    held = scene.with_inputs_held(dict(start_values or {}))
    if not held.inputs_varying_in_step and not held.switch_times():
        raise ModelInputError(
            f'--input-hold (inputs="hold"): every input of scene {scene.name} is constant in time'
            + (" (with the values set for this run)" if start_values else "")
            + ", so holding them over a step would change nothing; leave it out"
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


def run_length(stop_time: float, step: float) -> tuple[float, float]:
    """(stop_time, step) in s, checked: finite, > 0, and at most MAX_COMMUNICATION_POINTS
    steps (ModelInputError saying what is allowed)."""
    for label, v in (("stop_time", stop_time), ("step", step)):
        if not (np.isfinite(v) and v > 0):
            raise ModelInputError(f"{label} must be a finite number > 0, got {v}")
    n = stop_time / step
    if not n <= MAX_COMMUNICATION_POINTS:
        raise ModelInputError(
            f"stop_time {stop_time:g} s with step {step:g} s makes {n:.3g} communication steps; a run records every "
            f"output at each, at most {MAX_COMMUNICATION_POINTS:,}: take a larger step or a shorter stop time"
        )
    return float(stop_time), float(step)


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


def experiment(scene: Scene, stop_time: float | None = None, step: float | None = None) -> tuple[float, float]:
    """(stop time, communication step) in s: the given values, else the scene's, checked
    by `run_length` (finite, > 0, not too many communication points)."""
    return run_length(scene.stop_time if stop_time is None else stop_time, scene.step if step is None else step)


def simulate(
    inst: FmuInstance,
    scene: Scene,
    stop_time: float | None = None,
    step: float | None = None,
    start_values: Mapping[str, float] | None = None,
    input_fn: InputFunction | None = None,
    outputs: Sequence[str] | None = None,
    direct: bool = False,
    inputs: str = "continuous",
) -> RunResult:
    """Co-simulate on an instance that was just instantiated or reset (fmi3Reset): set
    the start values, initialise, step from t = 0 to stop_time (s) with communication
    step `step` (s). Arguments and result as `run_fmu`; this is its loop, shared with the
    sweeps (fmu.sweep.worker), which reuse one instance for many runs. direct: doStep and
    getFloat64 through `DirectCalls` instead of fmpy (the same calls, the same values).
    inputs "continuous" needs an instance created with node_inputs =
    `node_input_names(scene)` (ModelInputError otherwise)."""
    T, H = experiment(scene, stop_time, step)
    input_mode(inputs)
    scene = scene.with_inputs_held(dict(start_values or {}))  # a value given for an input replaces its schedule
    asked = node_input_names(scene, inputs) if input_fn is None else []
    missing = sorted(set(asked) - set(inst.node_inputs))
    if missing:
        raise ModelInputError(
            f"continuous inputs need an instance that asks for {', '.join(missing)} inside a step: create it with "
            "FmuInstance(..., node_inputs=node_input_names(scene)), or run with inputs='hold'"
        )
    inst.node_values = node_values(scene, inst.node_inputs) if asked else None
    out_names = list(outputs) if outputs else [v.name for v in inst.md.modelVariables if v.causality == "output"]
    in_names = [v.name for v in inst.md.modelVariables if v.causality == "input"]
    out_vrs = inst.value_references(out_names)
    inst.set(dict(start_values or {}))
    inst.initialize(0.0, T)
    grid = communication_points(scene, T, H)
    rows = np.empty((len(grid), len(out_names)))
    if direct:
        calls = inst.direct_calls()
        step_fn, read_row = calls.step, calls.reader(out_vrs)
    else:
        step_fn = inst.step

        def read_row(dst: np.ndarray) -> None:
            dst[:] = inst.get_float64(out_vrs)

    t0 = _time.perf_counter()
    if direct and not in_names:
        calls.run(grid, out_vrs, rows)
    else:
        held = {n: float(v) for n, v in (start_values or {}).items() if n in in_names}
        _step_loop(inst, scene, grid, rows, out_names, in_names, input_fn, step_fn, read_row, inputs, held)
    wall = _time.perf_counter() - t0
    return RunResult(
        scene=scene,
        time=grid,
        values={n: rows[:, k] for k, n in enumerate(out_names)},
        wall_time=wall,
        n_steps=len(grid) - 1,
    )


def _step_loop(
    inst: FmuInstance,
    scene: Scene,
    grid: np.ndarray,
    rows: np.ndarray,
    out_names: list[str],
    in_names: list[str],
    input_fn: InputFunction | None,
    step_fn: Callable[[float, float], None],
    read_row: Callable[[np.ndarray], None],
    inputs: str = "continuous",
    held: Mapping[str, float] | None = None,
) -> None:
    """The communication loop of `simulate`, with the inputs set before every step (from
    `input_fn`, the input components in `held` kept at their values; else the scene's
    schedules: their value at the step's start when continuous, their mean over the step
    when held)."""
    read_row(rows[0])
    for i in range(len(grid) - 1):
        t = grid[i]
        if in_names:
            if input_fn is not None:
                u = {**input_fn(t, dict(zip(out_names, rows[i]))), **(held or {})}
            else:
                u = {}
                for base in scene.inputs:
                    cont = inputs == "continuous"
                    val = scene.input_at(base, t) if cont else scene_input(scene, base, t, grid[i + 1])
                    u.update(zip(component_names(base), (float(x) for x in val)))
            inst.set(u)
        step_fn(t, grid[i + 1] - t)
        read_row(rows[i + 1])


def run_fmu(
    fmu_path: str | Path,
    scene: Scene,
    stop_time: float | None = None,
    step: float | None = None,
    start_values: Mapping[str, float] | None = None,
    input_fn: InputFunction | None = None,
    outputs: Sequence[str] | None = None,
    inputs: str = "continuous",
) -> RunResult:
    """Co-simulate the scene's FMU from t = 0 to stop_time with communication step `step`.

    start_values: name -> value set before initialisation (start state, parameters); a
    value for an input component ('f_thr_a[1]') holds it constant for the whole run,
    replacing the scene's schedule for it.
    input_fn(t, outputs) -> {input name: value}: called at every communication point with
    the latest outputs (closed loop; held over the step); without it, the scene's input
    schedules are used: inputs "continuous" (default) gives the FMU the physical input,
    inside a step too (FMI 3.0 intermediate update); "hold" holds each over a step at its
    mean there (`scene_input`), as an importer without intermediate update does.
    Returns every output (or the names in `outputs`) at every communication point.
    """
    T, H = experiment(scene, stop_time, step)
    held = scene.with_inputs_held(dict(start_values or {}))
    asked = node_input_names(held, inputs) if input_fn is None else []
    with FmuInstance(fmu_path, node_inputs=asked) as inst:
        return simulate(inst, scene, T, H, start_values, input_fn, outputs, inputs=inputs)
