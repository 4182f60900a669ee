"""One FMI 3.0 Co-Simulation instance driven through fmpy: names for value references, its log kept.

`FmuInstance` wraps fmpy's FMU3Slave: variables by name, the FMU's log messages collected
and attached to any error (`FmuError`), its warnings kept apart (the driver raises them as
`FmuWarning`s), the inputs asked at the FMU's internal nodes (FMI 3.0 intermediate update)
set from a Python function. `DirectCalls` makes the two calls of a communication step
(fmi3DoStep, fmi3GetFloat64) through ctypes without fmpy's per-call wrapper, for loops of
many runs (the sweeps).
"""

from __future__ import annotations

import contextlib
import ctypes
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave, fmi3LogMessageCallback

from modelsrc.errors import ModelInputError, unknown_variable


class FmuError(RuntimeError):
    """An FMI call failed; the message carries the FMU's own log messages."""


class FmuWarning(UserWarning):
    """The FMU logged a warning (fmi3Status Warning) during a run, which went on: the message is
    the FMU's own, with how often it was logged (docs/user_guide.md §3.2)."""


class WorkLimitError(FmuError):
    """A doStep was refused by the FMU's work limit (the tunable parameter work_limit,
    docs/fmi_layer.md, Work limit): the message names the limit, the time reached inside
    the step and how to raise it (docs/user_guide.md §3.2)."""


class EarlyEndError(FmuError):
    """A doStep returned without error but ended the run early (terminateSimulation or
    earlyReturn set): the run did not reach its stop time (docs/user_guide.md §3.2)."""


# How a user raises the limit, appended to the FMU's own message (which names the tunable parameter).
WORK_LIMIT_HINT = (
    " (rbfmu run: --set work_limit=N or a shorter --step; run_fmu, simulate: start_values={'work_limit': N}; "
    "at most 1e15)"
)


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
        self.warnings: list[str] = []  # the messages logged with status Warning, in order

        def _log(env, status, category, message):  # keep FMU messages for error reports, warnings to show
            text = message.decode("utf-8", "replace")
            self.messages.append(text)
            if status == FMI3_WARNING:
                self.warnings.append(text)

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
        """doStep(t, h) from the communication point t (s); sets `time` to t + h. A doStep
        that returns OK but ends the run early (terminateSimulation, earlyReturn) raises
        EarlyEndError: the outputs would stand for a time the FMU did not reach."""
        n = len(self.messages)
        result = self._call(self.fmu.doStep, lambda: f"doStep(t={t}, h={h})", t, h)
        self.raise_node_error()
        if result is not None and (result[1] or result[2]):
            raise self.early_end(t, h, bool(result[1]), float(result[3]), n)
        self.time = t + h

    def early_end(self, t: float, h: float, terminate: bool, reached: float, first_message: int) -> EarlyEndError:
        """The EarlyEndError of a doStep(t, h) that set terminateSimulation (terminate) or
        earlyReturn, having reached `reached` (s, its lastSuccessfulTime)."""
        flag = "terminateSimulation" if terminate else "earlyReturn"
        log = "; ".join(self.messages[first_message:]) or "the FMU logged nothing"
        return EarlyEndError(
            f"doStep(t={t}, h={h}) ended the run early: the FMU set {flag}, having reached t = {reached:g} s of "
            f"{t + h:g} s ({log})"
        )

    def reset(self) -> None:
        """fmi3Reset: back to the state after instantiation (start values restored)."""
        self._call(self.fmu.reset, "reset")
        self.time = 0.0

    def c_function(self, name: str):
        """The FMU library's C function `name` (ctypes), for loops that time the FMU's own
        work without fmpy's Python layer (fmu/bench/benchmark.py)."""
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
        if "work_limit" in log and what.startswith("doStep"):
            return WorkLimitError(f"{what} failed: {log}{WORK_LIMIT_HINT}")
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
        self._flags = (b(), b(), b(), ctypes.c_double())  # outputs of fmi3DoStep: terminate, early return checked
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
        self._check_early_end(t, h, n)
        self.inst.time = t + h

    def _check_early_end(self, t: float, h: float, first_message: int) -> None:
        """EarlyEndError when the last fmi3DoStep set terminateSimulation or earlyReturn."""
        _, terminate, early, reached = self._flags
        if terminate.value or early.value:
            raise self.inst.early_end(t, h, bool(terminate.value), reached.value, first_message)

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
        stop = self._flags[1:3]  # terminateSimulation, earlyReturn
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
            if stop[0].value or stop[1].value:
                self._check_early_end(t, h, n)
            if get(comp, c_vrs, k, address + (i + 1) * stride, k) > FMI3_WARNING:
                raise self.inst.failure("getFloat64", n)
        self.inst.time = ts[-1]
