"""A scene's FMU as an FMI 3.0 Model Exchange instance: states and inputs set, derivatives, outputs and Jacobians read.

Everything the linear models need from the FMU goes through standard FMI calls of fmpy's
FMU3Model, so that any importer could reproduce it: fmi3SetContinuousStates and
fmi3SetFloat64 put the instance at an operating point, fmi3GetContinuousStateDerivatives
and fmi3GetFloat64 read ẋ and y there, and fmi3GetDirectionalDerivative gives one column
J·e_j of the Jacobian of (ẋ, y) with respect to (x, u) per call (the FMU's CasADi
Jacobian, docs/fmi_layer.md, Directional and adjoint derivatives). Model Exchange, not the
Co-Simulation instance: only Model Exchange lets an importer set the continuous states
after initialisation, which a trim's Newton iteration needs (docs/fmi_layer.md §3).
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Model, fmi3LogMessageCallback

from modelsrc.errors import ModelInputError, unknown_variable

from ..drive.instance import FMI3_WARNING, FmuError, settable_variables


class ModelExchange:
    """One Model Exchange instance of an FMI 3.0 FMU, initialised and in continuous-time mode.

    states: the continuous states' names in the FMU's order (the modelDescription's
    derivatives); inputs, outputs: the names of its inputs and outputs in value-reference
    order; start_values: name -> value set before initialisation (start states,
    parameters, inputs, `method`), each checked to be settable and finite. Use as a
    context manager; `close()` frees the instance and removes the extracted archive.
    messages: every message the FMU logged (attached to an FmuError); warnings: those of
    status Warning, which the linear models raise as FmuWarnings when they are done
    (fmu.drive.logged_warnings.LoggedWarnings), as a run does.
    """

    def __init__(self, fmu_path: str | Path, start_values: Mapping[str, float] | None = None):
        self.path = Path(fmu_path)
        md = read_model_description(str(self.path))
        if md.modelExchange is None:
            raise ModelInputError(f"{self.path.name}: the FMU has no Model Exchange interface, which linearising needs")
        self.md = md
        self.variables = {v.name: v for v in md.modelVariables}
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.states = [d.variable.derivative.name for d in md.derivatives]
        self.state_names = tuple(self.states)  # as an operating point holds them (OperatingPoint.state_names)
        self.derivatives = [d.variable.name for d in md.derivatives]
        self.inputs = [v.name for v in md.modelVariables if v.causality == "input"]
        self.input_names = tuple(self.inputs)
        self.outputs = [v.name for v in md.modelVariables if v.causality == "output"]
        self.nominals = np.array([float(self.variables[s].nominal or 1.0) for s in self.states])
        values = dict(start_values or {})
        settable = settable_variables(md)
        for name, value in values.items():
            if name not in settable:
                raise unknown_variable(name, settable, known=self.vr)
            if not math.isfinite(float(value)):
                raise ModelInputError(f"{name} must be finite, got {value}")
        self.messages: list[str] = []
        self.warnings: list[str] = []  # the messages logged with status Warning, in order (raised by the callers)
        self._dir = extract(str(self.path))

        def log(env, status, category, message):  # the FMU's messages, attached to any error; its warnings to show
            text = message.decode("utf-8", "replace")
            self.messages.append(text)
            if status == FMI3_WARNING:
                self.warnings.append(text)

        self._log = fmi3LogMessageCallback(log)
        self.fmu = FMU3Model(
            guid=md.guid, unzipDirectory=self._dir, modelIdentifier=md.modelExchange.modelIdentifier, instanceName="lin"
        )
        self._open = False
        try:
            self._call(self.fmu.instantiate, "instantiate", logMessage=log)
            self._open = True
            floats = {n: float(v) for n, v in values.items() if self.variables[n].type == "Float64"}
            ints = {n: int(v) for n, v in values.items() if self.variables[n].type != "Float64"}
            if floats:
                self._call(
                    self.fmu.setFloat64, f"setting {', '.join(floats)}", self._vrs(floats), list(floats.values())
                )
            if ints:
                self._call(self.fmu.setInt64, f"setting {', '.join(ints)}", self._vrs(ints), list(ints.values()))
            self._call(self.fmu.enterInitializationMode, "enterInitializationMode", startTime=0.0)
            self._call(self.fmu.exitInitializationMode, "exitInitializationMode")
            self._call(self.fmu.updateDiscreteStates, "updateDiscreteStates")
            self._call(self.fmu.enterContinuousTimeMode, "enterContinuousTimeMode")
        except BaseException:
            self.close()
            raise
        self.nx = len(self.states)
        self.state_vrs = self._vrs(self.states)
        self.derivative_vrs = self._vrs(self.derivatives)
        # The calls a linearisation and its finite differences repeat, through ctypes with
        # every argument an address or a size (value references, seeds and results in
        # arrays made once): fmpy's wrappers convert their lists at every call (43 µs of
        # Python per directional derivative on quadrotor), and typed pointer arguments
        # cost 0.7 µs of conversion per call, either more than the FMU's own work. The
        # repeated calls go through prototypes without argtypes (`_u`) with their
        # arguments made once as ctypes objects (c_void_p, c_size_t), which ctypes passes
        # as they are: half the cost of a typed call of nine arguments (measured 3.2 against
        # 6.7 units on skewed_bar). The prototypes are made apart from fmpy's function
        # objects, whose argtypes stay.
        self._xbuf, self._dxbuf = np.zeros(self.nx), np.zeros(self.nx)
        self._xaddr, self._dxaddr = self._xbuf.ctypes.data, self._dxbuf.ctypes.data
        self._vr_cache: dict[tuple[int, ...], tuple[ctypes.Array, int]] = {}
        self._input_cache: dict[tuple[str, ...], tuple[np.ndarray, tuple]] = {}
        # what callers compute once per instance and reuse at every call (fmu.linear.linearize)
        self.plans: dict[tuple, object] = {}
        ptr, size = ctypes.c_void_p, ctypes.c_size_t
        signatures = {
            "directional": ("fmi3GetDirectionalDerivative", [ptr, ptr, size, ptr, size, ptr, size, ptr, size]),
            "get": ("fmi3GetFloat64", [ptr, ptr, size, ptr, size]),
            "set": ("fmi3SetFloat64", [ptr, ptr, size, ptr, size]),
            "set_states": ("fmi3SetContinuousStates", [ptr, ptr, size]),
            "get_states": ("fmi3GetContinuousStates", [ptr, ptr, size]),
            "rates": ("fmi3GetContinuousStateDerivatives", [ptr, ptr, size]),
        }
        self._c = {}
        self._u = {}
        for key, (name, argtypes) in signatures.items():
            address = ctypes.cast(getattr(self.fmu.dll, name), ctypes.c_void_p).value
            if address is None:
                raise FmuError(f"{self.path.name}: the FMU's library has no {name}")
            self._c[key] = ctypes.CFUNCTYPE(ctypes.c_int, *argtypes)(address)
            # no argument types declared: ctypes passes each argument as the ctypes object it is
            # (c_void_p, c_size_t: 64 bits each, as the typed prototype would)
            self._u[key] = ctypes.CFUNCTYPE(ctypes.c_int)(address)
        self._comp = ptr(self.fmu.component)
        self._set_x_args = (self._comp, ptr(self._xaddr), size(self.nx))
        self._rates_args = (self._comp, ptr(self._dxaddr), size(self.nx))

    def _vrs(self, names: Sequence[str] | Mapping[str, float]) -> list[int]:
        return [self.vr[n] for n in names]

    def _call(self, fn, what: str, *args, **kwargs):
        n = len(self.messages)
        try:
            return fn(*args, **kwargs)
        except (FMICallException, Exception) as exc:
            log = "; ".join(self.messages[n:]) or str(exc)
            raise FmuError(f"{what} failed: {log}") from exc

    def value_references(self, names: Sequence[str], allowed: Sequence[str], what: str) -> list[int]:
        """Value references of `names`, each one of `allowed` (ModelInputError naming it and
        listing what is allowed, e.g. the FMU's inputs or outputs)."""
        for n in names:
            if n not in allowed:
                raise unknown_variable(n, allowed, known=self.vr, listed=what)
        return self._vrs(names)

    def _check(self, status: int, what: str, n: int) -> None:
        if status > FMI3_WARNING:
            raise FmuError(f"{what} failed: {'; '.join(self.messages[n:]) or '(the FMU logged nothing)'}")

    def _vr_array(self, vrs: Sequence[int]) -> int:
        """The address of a fmi3ValueReference array of `vrs`, made once per list."""
        key = tuple(vrs)
        entry = self._vr_cache.get(key)
        if entry is None:
            arr = (ctypes.c_uint32 * len(key))(*key)
            entry = self._vr_cache[key] = (arr, ctypes.addressof(arr))
        return entry[1]

    def set_states(self, x: Sequence[float] | np.ndarray) -> None:
        """fmi3SetContinuousStates: the states (FMU order, FMU units)."""
        self._xbuf[:] = x
        status = self._u["set_states"](*self._set_x_args)
        if status > FMI3_WARNING:
            self._check(status, "setContinuousStates", len(self.messages))

    def states_now(self) -> np.ndarray:
        """fmi3GetContinuousStates."""
        self._check(self._c["get_states"](self.fmu.component, self._xaddr, self.nx), "getContinuousStates",
                    len(self.messages))  # fmt: skip
        return self._xbuf.copy()

    def set_inputs(self, values: Mapping[str, float]) -> None:
        """fmi3SetFloat64 of inputs by name."""
        if values:
            self._set_values(tuple(values), tuple(values.values()))

    def set_input_vector(self, u: np.ndarray) -> None:
        """fmi3SetFloat64 of every input, u in the FMU's order (`inputs`)."""
        if len(u):
            self._set_values(self.input_names, u)

    def _set_values(self, names: tuple[str, ...], values: Sequence[float] | np.ndarray) -> None:
        """fmi3SetFloat64 of the inputs `names` to `values`, through the values' buffer and the
        call's arguments made once per tuple of names (the names checked then)."""
        entry = self._input_cache.get(names)
        if entry is None:
            address = self._vr_array(self.value_references(names, self.inputs, "inputs"))
            buf, k = np.empty(len(names)), ctypes.c_size_t(len(names))
            entry = self._input_cache[names] = (buf, (self._comp, ctypes.c_void_p(address), k,
                                                      ctypes.c_void_p(buf.ctypes.data), k))  # fmt: skip
        buf, args = entry
        buf[:] = values
        status = self._u["set"](*args)
        if status > FMI3_WARNING:
            self._check(status, "setting inputs", len(self.messages))

    def rates(self) -> np.ndarray:
        """ẋ (fmi3GetContinuousStateDerivatives) at the states and inputs set."""
        status = self._u["rates"](*self._rates_args)
        if status > FMI3_WARNING:
            self._check(status, "getContinuousStateDerivatives", len(self.messages))
        return self._dxbuf.copy()

    def get(self, vrs: Sequence[int]) -> np.ndarray:
        """fmi3GetFloat64 by value reference."""
        k = len(vrs)
        out = np.empty(k)
        if k:
            n = len(self.messages)
            self._check(self._c["get"](self.fmu.component, self._vr_array(vrs), k, out.ctypes.data, k), "getFloat64", n)
        return out

    def jacobian(self, unknowns: Sequence[int], knowns: Sequence[int], seeds: np.ndarray | None = None) -> np.ndarray:
        """∂(unknowns)/∂(knowns) at the point set, one fmi3GetDirectionalDerivative per known
        (seed e_j: column j), or per column of `seeds` (len(knowns) × m: J·seeds, m calls).
        unknowns: value references of derivatives or outputs; knowns: of states or inputs."""
        nk = len(knowns)
        S = np.asfortranarray(np.eye(nk) if seeds is None else seeds, dtype=float)  # seed j: a contiguous column
        return self.directional_calls(unknowns, knowns, S)()

    def directional_calls(self, unknowns: Sequence[int], knowns: Sequence[int], seeds: np.ndarray,
                          rates_at: int | None = None):  # fmt: skip
        """The calls of `jacobian` made ready once: a function of no argument that returns
        J·seeds at the point set (len(unknowns) × m, a new array), one
        fmi3GetDirectionalDerivative per column of `seeds` (len(knowns) × m, Fortran order,
        kept and read at every call: its entries may change, its memory may not). What a
        linearisation repeats per point (fmu.linear.linearize.Plan) pays then the FMI calls
        alone: value references, seed addresses and sizes are found here, once. rates_at: a
        column k for ẋ at the point (fmi3GetContinuousStateDerivatives written straight into
        the result's rows of the derivatives; its rows of outputs are 0), the seeds' columns
        k, k + 1, ... then going to the result's k + 1, k + 2, ... (a linearisation's drift
        beside its Jacobian: one product reduces both, fmu.linear.linearize.assemble)."""
        if not (seeds.flags.f_contiguous and seeds.dtype == np.float64 and seeds.shape[0] == len(knowns)):
            raise ValueError("seeds: a Fortran-ordered float64 array of len(knowns) rows")
        nu, nk, m = len(unknowns), len(knowns), seeds.shape[1]
        V, Z = ctypes.c_void_p, ctypes.c_size_t
        c_unknowns, c_knowns = V(self._vr_array(unknowns)), V(self._vr_array(knowns))
        rows = [j + (rates_at is not None and j >= rates_at) for j in range(m)]  # the result's row of seed j
        J = np.zeros((m + (rates_at is not None), nu))  # row j: a column of the result, written in place by the FMU
        seed_at, at = seeds.ctypes.data, J.ctypes.data
        calls = [(self._comp, c_unknowns, Z(nu), c_knowns, Z(nk), V(seed_at + 8 * nk * j), Z(nk), V(at + 8 * nu * r),
                  Z(nu)) for j, r in enumerate(rows)]  # fmt: skip
        fn, rates = self._u["directional"], self._u["rates"]
        rates_args = None if rates_at is None else (self._comp, V(at + 8 * nu * rates_at), Z(self.nx))

        def run() -> np.ndarray:
            n = len(self.messages)
            if rates_args is not None and rates(*rates_args) > FMI3_WARNING:
                self._check(FMI3_WARNING + 1, "getContinuousStateDerivatives", n)
            for args in calls:
                if fn(*args) > FMI3_WARNING:
                    self._check(FMI3_WARNING + 1, "getDirectionalDerivative", n)
            keep = (seeds, J)  # the memory the calls' addresses point into
            # a C-ordered copy: the rows of the derivatives then are one block, which BLAS
            # multiplies as it is (a strided block is copied first: 0.2 µs, fmu.linear.bench)
            return keep[1].T.copy()

        return run

    def central_differences(self, outputs: Sequence[int], inputs: Sequence[int], x0: np.ndarray, u0: np.ndarray,
                            directions: np.ndarray, h: np.ndarray) -> np.ndarray:  # fmt: skip
        """Central differences of (ẋ, y) at the point (x0, u0) set: column k is
        (f(x0 + h_k d_k) − f(x0 − h_k d_k)) / (2 h_k) along the state direction d_k (column k
        of `directions`, nx × m), then one per input (fmi3SetFloat64 of u0_i ± h_{m+i}). Each
        evaluation is fmi3SetContinuousStates (or SetFloat64), GetContinuousStateDerivatives
        and GetFloat64 of `outputs`, written in place into preallocated buffers through the
        same ctypes calls as `jacobian`, so that the two cost what their FMI calls cost. The
        instance is left at (x0, u0). Returns ((nx + ny) × (m + nu))."""
        return self.difference_calls(outputs, inputs, directions.shape[1])(x0, u0, directions, h)

    def difference_calls(self, outputs: Sequence[int], inputs: Sequence[int], m: int, rates_at: bool = False):
        """The calls of `central_differences` made ready once, as `directional_calls` makes
        those of `jacobian`: a function (x0, u0, directions, h) -> the differences (a new
        array), the buffers of the evaluations, their addresses and the value references
        found here, once, so that the yardstick of a linearisation is as lean as it is.
        rates_at: the result has ẋ at (x0, u0) as its column m, between the directions' and
        the inputs', as `directional_calls(..., rates_at=m)` gives it; h then has m + 1 + nu
        entries, h[m] = ½ (that column's quotient (ẋ₀ − 0) / (2 · ½) is ẋ₀ itself, exactly)."""
        nx, ny, ni = self.nx, len(outputs), len(inputs)
        nf, r = nx + ny, int(rates_at)
        F = np.zeros((m + r + ni, 2, nf))  # F[k, 0]: f at the + step of column k, F[k, 1]: at the − step
        X = np.empty((m, 2, nx))  # X[k, s]: the state of evaluation (k, s), C order: a row per evaluation
        U = np.empty((ni, 3))  # u0 + h, u0 - h, u0 per input
        base, xbase, ubase = F.ctypes.data, X.ctypes.data, U.ctypes.data
        V, Z = ctypes.c_void_p, ctypes.c_size_t
        comp, c_out, znx, zny = self._comp, V(self._vr_array(outputs)), Z(nx), Z(ny)
        # evaluation j of the states: column j // 2, sign j % 2: the arguments of its three calls
        along_x = [
            ((comp, V(xbase + 8 * nx * j), znx), (comp, V(base + 8 * nf * j), znx),
             (comp, c_out, zny, V(base + 8 * nf * j + 8 * nx), zny))
            for j in range(2 * m)
        ]  # fmt: skip
        at_point = (comp, V(base + 8 * nf * 2 * m), znx) if rates_at else None  # ẋ₀ into F[m, 0]
        along_u = []
        for i in range(ni):
            c_in, one, f_at = V(self._vr_array(inputs[i : i + 1])), Z(1), base + 8 * nf * 2 * (m + r + i)
            along_u.append((
                [((comp, c_in, one, V(ubase + 8 * (3 * i + s)), one), (comp, V(f_at + 8 * nf * s), znx),
                  (comp, c_out, zny, V(f_at + 8 * nf * s + 8 * nx), zny)) for s in (0, 1)],
                (comp, c_in, one, V(ubase + 8 * (3 * i + 2)), one),
            ))  # fmt: skip
        setx, rates, get, setu = self._u["set_states"], self._u["rates"], self._u["get"], self._u["set"]
        what = "central differences (setContinuousStates, getContinuousStateDerivatives, getFloat64)"
        signs = np.array([1.0, -1.0, 0.0])

        def run(x0: np.ndarray, u0: np.ndarray, directions: np.ndarray, h: np.ndarray) -> np.ndarray:
            n = len(self.messages)
            steps = (directions * h[:m]).T
            np.add(x0, steps, out=X[:, 0])
            np.subtract(x0, steps, out=X[:, 1])
            U[:] = u0[:, None] + h[m + r :, None] * signs
            if ny:
                for sx, rt, g in along_x:
                    if setx(*sx) | rates(*rt) | get(*g) > FMI3_WARNING:
                        self._check(FMI3_WARNING + 1, what, n)
            else:
                for sx, rt, _ in along_x:
                    if setx(*sx) | rates(*rt) > FMI3_WARNING:
                        self._check(FMI3_WARNING + 1, what, n)
            self.set_states(x0)
            if at_point is not None and rates(*at_point) > FMI3_WARNING:
                self._check(FMI3_WARNING + 1, "getContinuousStateDerivatives", n)
            for evaluations, back in along_u:
                for su, rt, g in evaluations:
                    if (setu(*su) | rates(*rt) | (get(*g) if ny else 0)) > FMI3_WARNING:
                        self._check(FMI3_WARNING + 1, what.replace("setContinuousStates", "setFloat64"), n)
                self._check(setu(*back), "setting inputs", n)
            return np.divide((F[:, 0] - F[:, 1]).T, 2.0 * h, order="C")  # C order, as `directional_calls` gives

        return run

    def close(self) -> None:
        """Terminate (if the state allows), free the instance, remove the extracted files."""
        if self._open:
            with contextlib.suppress(FMICallException):  # a failed initialisation leaves nothing to terminate
                self.fmu.terminate()
            self.fmu.freeInstance()  # fmpy >= 0.3.32 also unloads the library here
            self._open = False
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self) -> ModelExchange:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
