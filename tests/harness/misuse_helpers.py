"""Helpers of the FMI misuse tests: instances brought into a given state, refusals with their log messages."""

from __future__ import annotations

from modelsrc.methods import METHODS

from .fmi3_ctypes import ERROR, OK, Fmi3Instance, Fmi3Library, shared_library

INST, INIT, STEP, TERM, ERR = "Instantiated", "InitializationMode", "StepMode", "Terminated", "Error"
STATES = (INST, INIT, STEP, TERM, ERR)


def in_state(lib: Fmi3Library, state: str) -> Fmi3Instance:
    """A Co-Simulation instance brought into `state` by legal calls (Error: through a
    start value that fails the checks of exitInitializationMode)."""
    inst = lib.instantiate()
    assert inst.handle, inst.log
    if state == INST:
        return inst
    if state == ERR:
        assert inst.set_float64([lib.info.vr["I_principal[1]"]], [-1.0]) == OK
    assert inst.enter_initialization_mode(0.0) == OK
    if state == INIT:
        return inst
    status = inst.exit_initialization_mode()
    assert status == (ERROR if state == ERR else OK), inst.log
    if state == TERM:
        assert inst.terminate() == OK
    return inst


def refused(inst: Fmi3Instance, status: int, n_log: int, *fragments: str) -> str:
    """Assert fmi3Error with an error message logged during the call containing every
    fragment; return the message text."""
    errors = inst.errors_since(n_log)
    assert status == ERROR, f"expected fmi3Error, got {status}; log {errors}"
    text = "\n".join(errors)
    for f in fragments:
        assert f in text, f"{f!r} not in the logged message {errors}"
    return text


def refused_at_exit_initialization(kind: str, name: str, value: float, fragment: str) -> None:
    """Assert that the start value `name` = `value` of the FMU `kind` is accepted by fmi3SetFloat64
    and then refused by fmi3ExitInitializationMode with a message containing `fragment`."""
    lib = shared_library(kind)
    inst = lib.instantiate()
    assert inst.set_float64([lib.info.vr[name]], [value]) == OK
    assert inst.enter_initialization_mode(0.0) == OK
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, "fmi3ExitInitializationMode", fragment)
    inst.free()


def c17(x: float) -> str:
    """x as the layer prints parameter values (C "%.17g": round-trip exact)."""
    return f"{x:.17g}"


def call(inst: Fmi3Instance, fn: str) -> int:
    """Perform `fn` with valid arguments (the state decides whether it is allowed)."""
    vr = inst.lib.info.vr
    method = inst.lib.info.int64_vrs["method"]
    return {
        "fmi3EnterInitializationMode": lambda: inst.enter_initialization_mode(0.0),
        "fmi3ExitInitializationMode": inst.exit_initialization_mode,
        "fmi3SetFloat64(state)": lambda: inst.set_float64([vr["w_body[1]"]], [0.5]),
        "fmi3SetFloat64(fixed parameter)": lambda: inst.set_float64([vr["I_principal[1]"]], [1.5]),
        "fmi3SetFloat64(input)": lambda: inst.set_float64([vr["tau_body[1]"]], [0.5]),
        "fmi3SetFloat64(tunable h_max)": lambda: inst.set_float64([vr["h_max"]], [2e-3]),
        "fmi3GetFloat64": lambda: inst.get_float64([vr["time"], vr["q[1]"], vr["E_kin"]])[0],
        "fmi3SetInt64(method)": lambda: inst.set_int64([method], [4]),
        "fmi3GetInt64(method)": lambda: inst.get_int64([method])[0],
        "fmi3DoStep": lambda: inst.do_step(
            inst.get_float64([0])[1][0] if inst.get_float64([0])[0] == OK else 0.0, 1e-3
        )[0],
        "fmi3Terminate": inst.terminate,
        "fmi3Reset": inst.reset,
        "fmi3SetDebugLogging": lambda: inst.set_debug_logging(True),
        "fmi3EnterEventMode": inst.enter_event_mode,
        "fmi3EnterStepMode": inst.enter_step_mode,
        "fmi3GetFMUState": lambda: _get_and_free_state(inst),
    }[fn]()


def _get_and_free_state(inst: Fmi3Instance) -> int:
    status, state = inst.get_fmu_state()
    if state.value:
        assert inst.free_fmu_state(state) == OK
    return status


# docs/fmi_layer.md, "States and what may be called in them" (Co-Simulation); the last
# three rows: no event mode in this Co-Simulation FMU; FMU state as rbfmu_fmi3.c allows it.
TABLE = {
    "fmi3EnterInitializationMode": {INST},
    "fmi3ExitInitializationMode": {INIT},
    "fmi3SetFloat64(state)": {INST, INIT},
    "fmi3SetFloat64(fixed parameter)": {INST, INIT},
    "fmi3SetFloat64(input)": {INST, INIT, STEP},
    "fmi3SetFloat64(tunable h_max)": {INST, INIT, STEP},
    "fmi3GetFloat64": {INIT, STEP, TERM, ERR},
    "fmi3SetInt64(method)": {INST, INIT, STEP},
    "fmi3GetInt64(method)": {INIT, STEP, TERM, ERR},
    "fmi3DoStep": {STEP},
    "fmi3Terminate": {STEP},  # as the Reference FMUs: not in InitializationMode
    "fmi3Reset": set(STATES),
    "fmi3SetDebugLogging": set(STATES),
    "fmi3EnterEventMode": set(),
    "fmi3EnterStepMode": set(),
    "fmi3GetFMUState": {INIT, STEP, TERM, ERR},
}


def stepping(lib: Fmi3Library, method: str | None = None, **values: float) -> Fmi3Instance:
    """An instance of lib in step mode at t = 0: `method` (by name) and the start values set
    before initialisation."""
    inst = lib.instantiate()
    if method is not None:
        assert inst.set_int64([lib.info.int64_vrs["method"]], [METHODS[method].value]) == OK
    if values:
        assert inst.set_float64([lib.info.vr[n] for n in values], list(values.values())) == OK
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK, inst.log
    return inst
