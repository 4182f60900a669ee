"""A small ctypes binding of the FMI 3.0 C API (Co-Simulation, Model Exchange, FMU state), for tests.

fmpy's FMU3Slave raises on every non-OK status and costs tens of µs per call; the
fuzzer (tests/robustness/test_fuzz_fmi.py) needs the raw status of ~10⁵ calls, including calls
that must fail, and every message the FMU logs during each call. This module calls
the shared library of an extracted FMU directly.

Signatures follow fmi3FunctionTypes.h of the FMI 3.0 standard (shipped with fmpy in
fmpy/c-code): fmi3Boolean is C99 `bool`, fmi3ValueReference `uint32_t`, fmi3Status an
enum (OK=0, Warning=1, Discard=2, Error=3, Fatal=4).
"""

from __future__ import annotations

import atexit
import ctypes as C
import dataclasses
import functools
import shutil
import tempfile
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree

OK, WARNING, DISCARD, ERROR, FATAL = range(5)
STATUS_NAMES = ("OK", "Warning", "Discard", "Error", "Fatal")

LOG_CALLBACK = C.CFUNCTYPE(None, C.c_void_p, C.c_int, C.c_char_p, C.c_char_p)
# fmi3IntermediateUpdateCallback(env, intermediateUpdateTime, intermediateVariableSetRequested,
# intermediateVariableGetAllowed, intermediateStepFinished, canReturnEarly, *earlyReturnRequested,
# *earlyReturnTime)
UPDATE_CALLBACK = C.CFUNCTYPE(
    None, C.c_void_p, C.c_double, C.c_bool, C.c_bool, C.c_bool, C.c_bool, C.POINTER(C.c_bool), C.POINTER(C.c_double)
)

_VR_P = C.POINTER(C.c_uint32)
_F64_P = C.POINTER(C.c_double)
_I64_P = C.POINTER(C.c_int64)
_BOOL_P = C.POINTER(C.c_bool)

# name -> (restype, argtypes) of the functions this binding calls.
_SIGNATURES: dict[str, tuple[object, list[object]]] = {
    "fmi3GetVersion": (C.c_char_p, []),
    "fmi3InstantiateCoSimulation": (
        C.c_void_p,
        [
            C.c_char_p,
            C.c_char_p,
            C.c_char_p,
            C.c_bool,
            C.c_bool,
            C.c_bool,
            C.c_bool,
            _VR_P,
            C.c_size_t,
            C.c_void_p,
            LOG_CALLBACK,
            C.c_void_p,  # intermediateUpdate: an UPDATE_CALLBACK cast to c_void_p, or None (NULL)
        ],
    ),
    "fmi3InstantiateModelExchange": (
        C.c_void_p,
        [C.c_char_p, C.c_char_p, C.c_char_p, C.c_bool, C.c_bool, C.c_void_p, LOG_CALLBACK],
    ),
    "fmi3FreeInstance": (None, [C.c_void_p]),
    "fmi3SetDebugLogging": (C.c_int, [C.c_void_p, C.c_bool, C.c_size_t, C.c_void_p]),
    "fmi3EnterInitializationMode": (C.c_int, [C.c_void_p, C.c_bool, C.c_double, C.c_double, C.c_bool, C.c_double]),
    "fmi3ExitInitializationMode": (C.c_int, [C.c_void_p]),
    "fmi3EnterEventMode": (C.c_int, [C.c_void_p]),
    "fmi3EnterStepMode": (C.c_int, [C.c_void_p]),
    "fmi3Terminate": (C.c_int, [C.c_void_p]),
    "fmi3Reset": (C.c_int, [C.c_void_p]),
    "fmi3GetFloat64": (C.c_int, [C.c_void_p, _VR_P, C.c_size_t, _F64_P, C.c_size_t]),
    "fmi3SetFloat64": (C.c_int, [C.c_void_p, _VR_P, C.c_size_t, _F64_P, C.c_size_t]),
    "fmi3GetInt64": (C.c_int, [C.c_void_p, _VR_P, C.c_size_t, _I64_P, C.c_size_t]),
    "fmi3SetInt64": (C.c_int, [C.c_void_p, _VR_P, C.c_size_t, _I64_P, C.c_size_t]),
    "fmi3GetFMUState": (C.c_int, [C.c_void_p, C.POINTER(C.c_void_p)]),
    "fmi3SetFMUState": (C.c_int, [C.c_void_p, C.c_void_p]),
    "fmi3FreeFMUState": (C.c_int, [C.c_void_p, C.POINTER(C.c_void_p)]),
    "fmi3SerializedFMUStateSize": (C.c_int, [C.c_void_p, C.c_void_p, C.POINTER(C.c_size_t)]),
    "fmi3SerializeFMUState": (C.c_int, [C.c_void_p, C.c_void_p, C.c_void_p, C.c_size_t]),
    "fmi3DeserializeFMUState": (C.c_int, [C.c_void_p, C.c_void_p, C.c_size_t, C.POINTER(C.c_void_p)]),
    "fmi3EnterContinuousTimeMode": (C.c_int, [C.c_void_p]),
    "fmi3CompletedIntegratorStep": (C.c_int, [C.c_void_p, C.c_bool, _BOOL_P, _BOOL_P]),
    "fmi3SetTime": (C.c_int, [C.c_void_p, C.c_double]),
    "fmi3SetContinuousStates": (C.c_int, [C.c_void_p, _F64_P, C.c_size_t]),
    "fmi3GetContinuousStates": (C.c_int, [C.c_void_p, _F64_P, C.c_size_t]),
    "fmi3GetContinuousStateDerivatives": (C.c_int, [C.c_void_p, _F64_P, C.c_size_t]),
    "fmi3UpdateDiscreteStates": (C.c_int, [C.c_void_p, _BOOL_P, _BOOL_P, _BOOL_P, _BOOL_P, _BOOL_P, _F64_P]),
    "fmi3DoStep": (C.c_int, [C.c_void_p, C.c_double, C.c_double, C.c_bool, _BOOL_P, _BOOL_P, _BOOL_P, _F64_P]),
    "fmi3GetNumberOfContinuousStates": (C.c_int, [C.c_void_p, C.POINTER(C.c_size_t)]),
    "fmi3GetOutputDerivatives": (C.c_int, [C.c_void_p, _VR_P, C.c_size_t, C.POINTER(C.c_int32), _F64_P, C.c_size_t]),
    "fmi3GetDirectionalDerivative": (
        C.c_int,
        [C.c_void_p, _VR_P, C.c_size_t, _VR_P, C.c_size_t, _F64_P, C.c_size_t, _F64_P, C.c_size_t],
    ),
    "fmi3GetAdjointDerivative": (
        C.c_int,
        [C.c_void_p, _VR_P, C.c_size_t, _VR_P, C.c_size_t, _F64_P, C.c_size_t, _F64_P, C.c_size_t],
    ),
}


@dataclass
class ModelInfo:
    """What a test needs from modelDescription.xml: the instantiation token, the
    modelIdentifier, value references by name, causality and variability by name,
    Float64 start values, the Int64/Enumeration variables with their start values,
    the enumeration items (value -> name) and the capability flags of <CoSimulation>."""

    token: str
    model_identifier: str
    vr: dict[str, int]
    causality: dict[str, str]
    variability: dict[str, str]
    start: dict[str, float]
    int64_vrs: dict[str, int]
    int64_start: dict[str, int]
    enum_items: dict[int, str]
    cs_flags: dict[str, str] = field(default_factory=dict)


def read_model_info(unzipdir: Path) -> ModelInfo:
    """Parse modelDescription.xml of an extracted FMU (plain ElementTree, no fmpy)."""
    root = ElementTree.parse(unzipdir / "modelDescription.xml").getroot()
    cs = root.find("CoSimulation")
    if cs is None:
        raise ValueError(f"{unzipdir}: no <CoSimulation> element")
    vr, causality, variability, start, int64, int64_start = {}, {}, {}, {}, {}, {}
    for var in root.find("ModelVariables"):
        name = var.get("name")
        vr[name] = int(var.get("valueReference"))
        causality[name] = var.get("causality", "local")
        variability[name] = var.get("variability", "continuous")
        if var.get("start") is not None and var.tag == "Float64":
            start[name] = float(var.get("start"))
        if var.tag in ("Int64", "Enumeration"):
            int64[name] = vr[name]
            if var.get("start") is not None:
                int64_start[name] = int(var.get("start"))
    items = {int(item.get("value")): item.get("name") for item in root.iter("Item")}
    return ModelInfo(
        token=root.get("instantiationToken"),
        model_identifier=cs.get("modelIdentifier"),
        vr=vr,
        causality=causality,
        variability=variability,
        start=start,
        int64_vrs=int64,
        int64_start=int64_start,
        enum_items=items,
        cs_flags=dict(cs.attrib),
    )


def extract_fmu(fmu: Path, dest: Path) -> Path:
    """Unzip an .fmu into dest (created) and return dest."""
    dest.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(dest)
    return dest


class Fmi3Library:
    """The shared library of one extracted FMU with typed function pointers."""

    def __init__(
        self, unzipdir: Path, platform: str = "x86_64-linux", so_path: Path | None = None, mode: int = C.DEFAULT_MODE
    ):
        """Load binaries/<platform>/<modelIdentifier>.so of an extracted FMU, or the
        library so_path built from the same FMU's sources (e.g. tests/c/introspect.c);
        mode: dlopen's (C.RTLD_GLOBAL puts its exports into the process's namespace)."""
        self.unzipdir = Path(unzipdir)
        self.info = read_model_info(self.unzipdir)
        self.so_path = (
            Path(so_path) if so_path else self.unzipdir / "binaries" / platform / f"{self.info.model_identifier}.so"
        )
        self.dll = C.CDLL(str(self.so_path), mode=mode)
        for name, (restype, argtypes) in _SIGNATURES.items():
            fn = getattr(self.dll, name)
            fn.restype, fn.argtypes = restype, argtypes
            setattr(self, name[4:], fn)  # e.g. self.DoStep

    def instantiate(
        self,
        name: str | None = "inst",
        token: str | None = None,
        logging_on: bool = False,
        event_mode_used: bool = False,
        model_exchange: bool = False,
        intermediate_update: Callable[[float], None] | None = None,
        required: Sequence[int] = (),
    ) -> Fmi3Instance:
        """fmi3InstantiateCoSimulation (or fmi3InstantiateModelExchange); `token` defaults
        to the modelDescription's. intermediate_update(t) is the importer's intermediate-update
        callback (FMI 3.0 §4.2.3; t in s), with `required` the value references it will set
        (requiredIntermediateVariables). Returns an Fmi3Instance whose .handle is None when
        the FMU returned NULL."""
        return Fmi3Instance(
            self,
            name,
            self.info.token if token is None else token,
            logging_on,
            event_mode_used,
            model_exchange,
            intermediate_update,
            required,
        )


class Fmi3Instance:
    """One instance; every call returns the raw fmi3Status and appends the messages
    the FMU logs to .log as (status, category, message) tuples."""

    def __init__(
        self,
        lib: Fmi3Library,
        name: str | None,
        token: str,
        logging_on: bool,
        event_mode_used: bool,
        model_exchange: bool = False,
        intermediate_update: Callable[[float], None] | None = None,
        required: Sequence[int] = (),
    ):
        self.lib = lib
        self.model_exchange = model_exchange
        self.log: list[tuple[int, str, str]] = []

        def _log(env, status, category, message):
            self.log.append(
                (int(status), (category or b"").decode("utf-8", "replace"), (message or b"").decode("utf-8", "replace"))
            )

        self._cb = LOG_CALLBACK(_log)  # kept alive as long as the instance
        self._update = UPDATE_CALLBACK()  # NULL: no intermediate update
        # (intermediateVariableSetRequested, ...GetAllowed, intermediateStepFinished, canReturnEarly) of the last call
        self.update_flags: tuple[bool, ...] = ()
        if intermediate_update is not None:

            def _update(env, t, set_requested, get_allowed, finished, can_return, early, early_time):
                self.update_flags = (bool(set_requested), bool(get_allowed), bool(finished), bool(can_return))
                intermediate_update(t)

            self._update = UPDATE_CALLBACK(_update)
        req = (C.c_uint32 * max(1, len(required)))(*required)
        bname = None if name is None else name.encode()
        if model_exchange:
            self.handle = lib.InstantiateModelExchange(bname, token.encode(), None, False, logging_on, None, self._cb)
        else:
            self.handle = lib.InstantiateCoSimulation(
                bname,
                token.encode(),
                None,
                False,
                logging_on,
                event_mode_used,
                False,
                req if required else None,
                len(required),
                None,
                self._cb,
                C.cast(self._update, C.c_void_p),
            )

    # --- small wrappers; arrays are built per call (the fuzzer's calls are short) ---
    def free(self) -> None:
        if self.handle:
            self.lib.FreeInstance(self.handle)
            self.handle = None

    def set_debug_logging(self, on: bool) -> int:
        return self.lib.SetDebugLogging(self.handle, on, 0, None)

    def enter_initialization_mode(
        self, start_time: float = 0.0, stop_time: float | None = None, tolerance: float | None = None
    ) -> int:
        """fmi3EnterInitializationMode; tolerance: the importer's (None: toleranceDefined = false)."""
        return self.lib.EnterInitializationMode(
            self.handle,
            tolerance is not None,
            0.0 if tolerance is None else tolerance,
            start_time,
            stop_time is not None,
            0.0 if stop_time is None else stop_time,
        )

    def exit_initialization_mode(self) -> int:
        return self.lib.ExitInitializationMode(self.handle)

    def terminate(self) -> int:
        return self.lib.Terminate(self.handle)

    def reset(self) -> int:
        return self.lib.Reset(self.handle)

    def enter_event_mode(self) -> int:
        return self.lib.EnterEventMode(self.handle)

    def enter_step_mode(self) -> int:
        return self.lib.EnterStepMode(self.handle)

    def get_fmu_state(self, state: C.c_void_p | None = None) -> tuple[int, C.c_void_p]:
        """fmi3GetFMUState into `state` (a new one when None or NULL); returns (status, state)."""
        state = C.c_void_p() if state is None else state
        return self.lib.GetFMUState(self.handle, C.byref(state)), state

    def set_fmu_state(self, state: C.c_void_p | None) -> int:
        return self.lib.SetFMUState(self.handle, state)

    def free_fmu_state(self, state: C.c_void_p) -> int:
        """fmi3FreeFMUState; sets state to NULL like the FMU does."""
        return self.lib.FreeFMUState(self.handle, C.byref(state))

    def serialized_size(self, state: C.c_void_p | None) -> tuple[int, int]:
        size = C.c_size_t(0)
        return self.lib.SerializedFMUStateSize(self.handle, state, C.byref(size)), size.value

    def serialize(self, state: C.c_void_p | None, size: int) -> tuple[int, bytes]:
        buf = (C.c_ubyte * max(1, size))()
        status = self.lib.SerializeFMUState(self.handle, state, buf, size)
        return status, bytes(buf[:size])

    def deserialize(self, data: bytes) -> tuple[int, C.c_void_p]:
        buf = (C.c_ubyte * max(1, len(data))).from_buffer_copy(data + b"\0")
        state = C.c_void_p()
        return self.lib.DeserializeFMUState(self.handle, buf, len(data), C.byref(state)), state

    # --- Model Exchange ---
    def enter_continuous_time_mode(self) -> int:
        return self.lib.EnterContinuousTimeMode(self.handle)

    def completed_integrator_step(self) -> int:
        b1, b2 = C.c_bool(), C.c_bool()
        return self.lib.CompletedIntegratorStep(self.handle, True, C.byref(b1), C.byref(b2))

    def set_time(self, t: float) -> int:
        return self.lib.SetTime(self.handle, t)

    def set_continuous_states(self, x: Sequence[float]) -> int:
        return self.lib.SetContinuousStates(self.handle, (C.c_double * max(1, len(x)))(*x), len(x))

    def get_continuous_states(self, n: int) -> tuple[int, list[float]]:
        x = (C.c_double * max(1, n))()
        return self.lib.GetContinuousStates(self.handle, x, n), list(x[:n])

    def get_derivatives(self, n: int) -> tuple[int, list[float]]:
        x = (C.c_double * max(1, n))()
        return self.lib.GetContinuousStateDerivatives(self.handle, x, n), list(x[:n])

    def update_discrete_states(self) -> int:
        b = [C.c_bool() for _ in range(5)]
        t = C.c_double()
        return self.lib.UpdateDiscreteStates(self.handle, *[C.byref(x) for x in b], C.byref(t))

    def set_float64(self, vrs: Sequence[int], values: Sequence[float], n_values: int | None = None) -> int:
        """fmi3SetFloat64; n_values (default len(values)) lets a test pass a wrong count."""
        v = (C.c_uint32 * max(1, len(vrs)))(*vrs)
        x = (C.c_double * max(1, len(values)))(*values)
        return self.lib.SetFloat64(self.handle, v, len(vrs), x, len(values) if n_values is None else n_values)

    def get_float64(self, vrs: Sequence[int], n_values: int | None = None) -> tuple[int, list[float]]:
        n = len(vrs) if n_values is None else n_values
        v = (C.c_uint32 * max(1, len(vrs)))(*vrs)
        x = (C.c_double * max(1, n, len(vrs)))()
        status = self.lib.GetFloat64(self.handle, v, len(vrs), x, n)
        return status, list(x[: len(vrs)])

    def set_int64(self, vrs: Sequence[int], values: Sequence[int]) -> int:
        v = (C.c_uint32 * max(1, len(vrs)))(*vrs)
        x = (C.c_int64 * max(1, len(values)))(*values)
        return self.lib.SetInt64(self.handle, v, len(vrs), x, len(values))

    def get_int64(self, vrs: Sequence[int]) -> tuple[int, list[int]]:
        v = (C.c_uint32 * max(1, len(vrs)))(*vrs)
        x = (C.c_int64 * max(1, len(vrs)))()
        status = self.lib.GetInt64(self.handle, v, len(vrs), x, len(vrs))
        return status, list(x[: len(vrs)])

    def do_step(self, t: float, h: float) -> tuple[int, float]:
        """fmi3DoStep(t, h); returns (status, lastSuccessfulTime)."""
        b1, b2, b3 = C.c_bool(), C.c_bool(), C.c_bool()
        last = C.c_double(float("nan"))
        status = self.lib.DoStep(self.handle, t, h, False, C.byref(b1), C.byref(b2), C.byref(b3), C.byref(last))
        return status, last.value

    def get_output_derivatives(
        self, vrs: Sequence[int], orders: Sequence[int], n_values: int | None = None
    ) -> tuple[int, list[float]]:
        """fmi3GetOutputDerivatives; n_values (default len(vrs)) lets a test pass a wrong count."""
        n = len(vrs)
        v = (C.c_uint32 * max(1, n))(*vrs)
        o = (C.c_int32 * max(1, n))(*orders)
        x = (C.c_double * max(1, n))()
        status = self.lib.GetOutputDerivatives(self.handle, v, n, o, x, n if n_values is None else n_values)
        return status, list(x[:n])

    def get_directional(
        self, unknowns: Sequence[int], knowns: Sequence[int], seed: Sequence[float], adjoint: bool = False
    ) -> tuple[int, list[float]]:
        """fmi3GetDirectionalDerivative (or, adjoint=True, fmi3GetAdjointDerivative): the
        sensitivity J·seed (or seedᵀ·J), J = d unknowns / d knowns at the current state."""
        n_sens = len(knowns) if adjoint else len(unknowns)
        u = (C.c_uint32 * max(1, len(unknowns)))(*unknowns)
        k = (C.c_uint32 * max(1, len(knowns)))(*knowns)
        sd = (C.c_double * max(1, len(seed)))(*seed)
        sens = (C.c_double * max(1, n_sens))()
        fn = self.lib.GetAdjointDerivative if adjoint else self.lib.GetDirectionalDerivative
        status = fn(self.handle, u, len(unknowns), k, len(knowns), sd, len(seed), sens, n_sens)
        return status, list(sens[:n_sens])

    def errors_since(self, n: int) -> list[str]:
        """Messages logged with a non-OK status since the log had n entries."""
        return [m for s, _, m in self.log[n:] if s != OK]


# ---- FMUs shared by the robustness tests (built once per process) ----

# A torque-free principal body with every knob the robustness tests turn through start
# values: body-frame torque inputs, viscous friction (c = 0 by default: the friction
# torque -c w is then exactly zero), all derived outputs, all six methods.
EXTREME_FREE_TOML = """
name = "extreme_free"
description = "Free principal body I = diag(1, 2, 3), body torque inputs, viscous friction (c = 0 by default)."
outputs = ["q", "w_body", "w_world", "euler_zxz", "E_kin", "E_total", "L_world", "L_body"]
[features]
torque_body = true
friction = true
[body]
principal_moments = [1.0, 2.0, 3.0]
[friction]
c = 0.0
[initial]
w_body = [0.0, 0.0, 1.0]
[experiment]
stop_time = 1.0
step = 0.01
h_max = 0.001
tolerance = 0.0
method = "rk4"
"""

# ASan + UBSan build (tests/robustness/test_fuzz_fmi.py). -O0: the sanitizers work at every
# level (-O1 is recommended only for run-time speed), and with -g at -O1 gcc spends minutes on
# the large generated model_funcs.c of the rotor scenes (quadrotor's 456 kB: 412 s at -O1 -g,
# 146 s at -O1, 60 s at -O0 -g, measured on 2 loaded cores, gcc 12) while the fuzz runs
# themselves take seconds; nothing is optimised away at -O0, so no check is lost.
# -g puts file:line into the sanitizer reports.
SANITIZER_CFLAGS = ("-fsanitize=address,undefined", "-fno-omit-frame-pointer", "-O0", "-g")

_BUILD_ROOT: Path | None = None


def _build_root() -> Path:
    global _BUILD_ROOT
    if _BUILD_ROOT is None:
        _BUILD_ROOT = Path(tempfile.mkdtemp(prefix="rbfmu_robust_"))
        atexit.register(shutil.rmtree, _BUILD_ROOT, True)
    return _BUILD_ROOT


@functools.cache
def shared_fmu(kind: str, sanitize: bool = False) -> Path:
    """Path of a built FMU: kind "extreme_free" (EXTREME_FREE_TOML), a scene of
    tests/harness/fuzz_scenes.py ("offaxis_wheel", "central_wheel") or a shipped scene
    name (e.g. "sleeping_top"); sanitize=True adds SANITIZER_CFLAGS. Built once per
    process (~3 s each, ~6 s sanitized) into a temporary directory removed at exit.
    These FMUs take fixed steps by default (tolerance 0, h_max the scene's fixed step,
    rk4, docs/theory.md §5.4): the extreme-case and fuzz tests predict fixed-step errors
    and work; error-controlled stepping has its own tests (tests/physics/test_error_control.py)."""
    from fmu.build.build_fmu import build_fmu
    from modelsrc.scene import load_scene

    from .fuzz_scenes import FUZZ_SCENES

    out = _build_root() / (kind + ("_asan" if sanitize else ""))
    user = {"extreme_free": EXTREME_FREE_TOML, **FUZZ_SCENES}.get(kind)
    if user is not None:
        out.mkdir(parents=True, exist_ok=True)
        (out / f"{kind}.toml").write_text(user)
        scene = load_scene(out / f"{kind}.toml")
    else:
        sc = load_scene(kind)
        scene = dataclasses.replace(sc, tolerance=0.0, h_max=sc.fixed_step, method="rk4")
    return build_fmu(scene, out, extra_cflags=list(SANITIZER_CFLAGS) if sanitize else None)


@functools.cache
def shared_library(kind: str) -> Fmi3Library:
    """The extracted, loaded (non-sanitized) FMU of shared_fmu(kind)."""
    fmu = shared_fmu(kind)
    return Fmi3Library(extract_fmu(fmu, fmu.parent / "unzipped"))
