"""FMI misuse and bad input: every refusal is fmi3Error plus a logged message that names
the function and the offending value, and the instance stays consistent.

Deterministic companion of the fuzzer (tests/test_fuzz_fmi.py): the state table of
docs/fmi_layer.md cell by cell, then each kind of bad input once, through the raw
FMI 3.0 C API (tests/fmi3_ctypes.py) so that statuses and log messages are seen as an
importer sees them. Scene-file errors extend tests/test_bad_input.py (not repeated).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene

from .conftest import write_scene
from .fmi3_ctypes import ERROR, LOG_CALLBACK, OK, Fmi3Instance, Fmi3Library, shared_library

INST, INIT, STEP, TERM, ERR = "Instantiated", "InitializationMode", "StepMode", "Terminated", "Error"
STATES = (INST, INIT, STEP, TERM, ERR)


@pytest.fixture(scope="module")
def free_lib() -> Fmi3Library:
    """extreme_free: free principal body, torque inputs, friction (tests/fmi3_ctypes.py)."""
    return shared_library("extreme_free")


@pytest.fixture(scope="module")
def top_lib() -> Fmi3Library:
    """The shipped sleeping_top: gravity (mass, r_cm, g) and friction."""
    return shared_library("sleeping_top")


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


def c17(x: float) -> str:
    """x as the layer prints parameter values (C "%.17g": round-trip exact)."""
    return "%.17g" % x


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


@pytest.mark.parametrize("state", STATES)
def test_state_table(free_lib, state):
    """Each function in each state: allowed -> fmi3OK and no error logged; not allowed ->
    fmi3Error and a message naming the function and the state (or, for a variable not
    settable in a state where setting is allowed, naming the variable and the state)."""
    bad = []
    for fn, allowed in TABLE.items():
        inst = in_state(free_lib, state)
        n = len(inst.log)
        status = call(inst, fn)
        errors = inst.errors_since(n)
        name = fn.split("(")[0]
        if state in allowed:
            if status != OK or errors:
                bad.append(f"{fn} in {state}: must succeed, got {status} {errors}")
        elif status != ERROR:
            bad.append(f"{fn} in {state}: must be refused, got status {status}")
        elif not any(name in e and state in e for e in errors):
            bad.append(f"{fn} in {state}: refused without a message naming it and the state: {errors}")
        inst.free()
    assert not bad, "\n".join(bad)


# ---- non-finite values: refused at set time, naming variable and value; nothing changes ----


@pytest.mark.parametrize("name", ["tau_body[2]", "I_principal[2]", "c_friction", "h_max", "w_body[3]", "q[1]"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_non_finite_values_refused(free_lib, name, value):
    inst = in_state(free_lib, INIT)
    vr = free_lib.info.vr[name]
    before = inst.get_float64([vr])[1]
    n = len(inst.log)
    refused(inst, inst.set_float64([vr], [value]), n, "fmi3SetFloat64", f"'{name}'", f"must be finite, got {value}")
    assert inst.get_float64([vr])[1] == before  # unchanged
    assert inst.exit_initialization_mode() == OK  # and the instance is still usable
    inst.free()


@pytest.mark.parametrize("name", ["mass", "r_cm[1]", "g[3]"])
def test_non_finite_gravity_parameters_refused(top_lib, name):
    inst = in_state(top_lib, INST)
    n = len(inst.log)
    refused(inst, inst.set_float64([top_lib.info.vr[name]], [math.nan]), n, f"'{name}'", "must be finite, got nan")
    inst.free()


def test_non_finite_input_in_step_mode_refused_and_run_continues(free_lib):
    inst = in_state(free_lib, STEP)
    vr = free_lib.info.vr["tau_body[1]"]
    n = len(inst.log)
    refused(
        inst,
        inst.set_float64([vr, free_lib.info.vr["tau_body[2]"]], [1.0, math.inf]),
        n,
        "'tau_body[2]'",
        "must be finite, got inf",
    )
    assert inst.get_float64([vr])[1] == [0.0]  # all or nothing: tau_body[1] not set either
    assert inst.do_step(0.0, 1e-2)[0] == OK
    inst.free()


# ---- invalid parameters: refused at exitInitializationMode, naming check and values ----


@pytest.mark.parametrize(
    "moments, check",
    [
        ((-1.0, 2.0, 3.0), "inertia must be positive definite"),
        ((0.0, 1.0, 1.0), "inertia must be positive definite"),
        ((1.0, 2.0, 3.5), "I_i + I_j >= I_k"),
    ],
)
def test_invalid_inertia_refused_at_initialisation(free_lib, moments, check):
    inst = in_state(free_lib, INST)
    vrs = [free_lib.info.vr[f"I_principal[{k}]"] for k in (1, 2, 3)]
    assert inst.set_float64(vrs, list(moments)) == OK  # checked as a whole, at initialisation
    assert inst.enter_initialization_mode(0.0) == OK
    n = len(inst.log)
    text = refused(inst, inst.exit_initialization_mode(), n, "fmi3ExitInitializationMode", check, "parameter values:")
    for k, v in enumerate(moments, 1):
        assert f"I_principal[{k}]={c17(v)}" in text
    n = len(inst.log)  # the instance is in the Error state: no stepping, values readable
    refused(inst, inst.do_step(0.0, 1e-3)[0], n, "fmi3DoStep: not allowed in state Error")
    assert inst.get_float64([vrs[0]]) == (OK, [moments[0]])
    assert inst.reset() == OK  # and Reset brings it back to the start values
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    inst.free()


@pytest.mark.parametrize("mass", [-0.5, 0.0])
def test_non_positive_mass_refused(top_lib, mass):
    inst = in_state(top_lib, INST)
    assert inst.set_float64([top_lib.info.vr["mass"]], [mass]) == OK
    assert inst.enter_initialization_mode(0.0) == OK
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, "mass must be > 0", f"mass={c17(mass)}")
    inst.free()


def test_negative_friction_refused(free_lib):
    inst = in_state(free_lib, INIT)
    assert inst.set_float64([free_lib.info.vr["c_friction"]], [-1e-3]) == OK
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, "c_friction must be >= 0", f"c_friction={c17(-1e-3)}")
    inst.free()


def test_splitting_with_off_axis_centre_of_mass_refused_in_step_mode(top_lib):
    """The splitting needs principal axes about the pivot (docs/theory.md §5.3): with r_cm off
    the body axes, selecting it is refused at initialisation and, in step mode, the change of
    the tunable `method` is refused and the old method kept."""
    vr, method_vr = top_lib.info.vr, top_lib.info.int64_vrs["method"]
    split = next(v for v, n in top_lib.info.enum_items.items() if n == "splitting")
    inst = in_state(top_lib, INST)
    assert inst.set_float64([vr["r_cm[1]"], vr["r_cm[3]"]], [0.03, 0.04]) == OK
    assert inst.set_int64([method_vr], [split]) == OK
    assert inst.enter_initialization_mode(0.0) == OK
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, "method splitting needs principal axes", f"r_cm[1]={c17(0.03)}")
    assert inst.reset() == OK
    assert inst.set_float64([vr["r_cm[1]"], vr["r_cm[3]"]], [0.03, 0.04]) == OK
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    n = len(inst.log)
    refused(inst, inst.set_int64([method_vr], [split]), n, "fmi3SetInt64", "method splitting needs principal axes")
    assert inst.get_int64([method_vr]) == (OK, [top_lib.info.int64_start["method"]])
    inst.free()


@pytest.mark.parametrize("h_max", [0.0, -1e-3])
def test_non_positive_h_max(free_lib, h_max):
    vr = free_lib.info.vr["h_max"]
    inst = in_state(free_lib, INIT)  # at initialisation
    assert inst.set_float64([vr], [h_max]) == OK
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, "h_max must be > 0", f"h_max={c17(h_max)}")
    inst.free()
    inst = in_state(free_lib, STEP)  # in step mode (h_max is tunable): refused, old value kept
    n = len(inst.log)
    refused(inst, inst.set_float64([vr], [h_max]), n, "fmi3SetFloat64", "h_max must be > 0")
    assert inst.get_float64([vr]) == (OK, [free_lib.info.start["h_max"]])
    assert inst.do_step(0.0, 1e-2)[0] == OK
    inst.free()


# ---- doStep arguments ----


@pytest.mark.parametrize("h", [0.0, -1e-3, math.nan, math.inf, -math.inf])
def test_bad_communication_step_refused(free_lib, h):
    inst = in_state(free_lib, STEP)
    n = len(inst.log)
    status, last = inst.do_step(0.0, h)
    refused(inst, status, n, "communicationStepSize must be finite and > 0", f"got {h:g}")
    assert last == 0.0 and inst.get_float64([0]) == (OK, [0.0])  # time unchanged
    assert inst.do_step(0.0, 1e-2)[0] == OK  # still usable
    inst.free()


@pytest.mark.parametrize(
    "start, offset, ok",
    [
        (0.0, 1e-3, False),
        (0.0, -1e-3, False),
        (0.0, math.nan, False),
        (0.0, 5e-11, True),  # within the tolerance 1e-10 max(1, |t|)
        (1e6, 5e-5, True),  # relative tolerance: 1e-10 * 1e6 = 1e-4
        (1e6, 2e-4, False),
    ],
)
def test_communication_point_must_be_current_time(free_lib, start, offset, ok):
    inst = free_lib.instantiate()
    assert inst.enter_initialization_mode(start) == OK and inst.exit_initialization_mode() == OK
    n = len(inst.log)
    status, last = inst.do_step(start + offset, 1e-3)
    if ok:
        assert status == OK and last == start + offset + 1e-3, inst.log
    else:
        refused(inst, status, n, "currentCommunicationPoint", f"current time {start:.17g}")
        assert last == start
    inst.free()


def test_step_needing_more_than_1e8_substeps_refused(free_lib):
    vr = free_lib.info.vr
    inst = in_state(free_lib, STEP)
    assert inst.set_float64([vr["h_max"]], [1e-12]) == OK  # valid, but 1e-2/1e-12 = 1e10 substeps
    states = [vr[f"q[{k}]"] for k in range(1, 5)] + [vr[f"w_body[{k}]"] for k in range(1, 4)]
    before = inst.get_float64(states)[1]
    n = len(inst.log)
    refused(
        inst,
        inst.do_step(0.0, 1e-2)[0],
        n,
        "needs 1e+10 internal steps",
        "more than the limit 100000000",
        "h_max 1e-12",
    )
    assert inst.get_float64(states)[1] == before and inst.get_float64([0])[1] == [0.0]
    assert inst.set_float64([vr["h_max"]], [1e-3]) == OK and inst.do_step(0.0, 1e-2)[0] == OK
    inst.free()


def test_overflowing_state_refused_and_restored(free_lib):
    """A torque so large that the state overflows: after the retries the step is refused
    with a message, the state and time are those before the step, and the instance stays
    in step mode (docs/fmi_layer.md): with a sane torque it steps on."""
    vr = free_lib.info.vr
    inst = in_state(free_lib, STEP)
    states = [vr[f"q[{k}]"] for k in range(1, 5)] + [vr[f"w_body[{k}]"] for k in range(1, 4)]
    before = inst.get_float64(states)[1]
    assert inst.set_float64([vr["tau_body[1]"]], [1e200]) == OK
    n = len(inst.log)
    refused(inst, inst.do_step(0.0, 1e-2)[0], n, "the state became non-finite", "the state is left at t=0")
    assert inst.get_float64(states)[1] == before and inst.get_float64([0])[1] == [0.0]
    assert inst.set_float64([vr["tau_body[1]"]], [1.0]) == OK
    assert inst.do_step(0.0, 1e-2)[0] == OK
    inst.free()


# ---- unknown value references, wrong counts ----


def test_unknown_value_references(free_lib):
    inst = in_state(free_lib, STEP)
    nv = max(free_lib.info.vr.values()) + 1
    float_nv = nv - 1  # the last value reference is the Int64 `method`
    for vr in (float_nv, 2**32 - 1):
        n = len(inst.log)
        refused(inst, inst.set_float64([vr], [1.0]), n, "fmi3SetFloat64", f"value reference {vr}")
        n = len(inst.log)
        refused(inst, inst.get_float64([vr])[0], n, "fmi3GetFloat64", f"value reference {vr}")
    for vr in (0, 2**32 - 1):  # Int64 access to a Float64 variable / to nothing
        n = len(inst.log)
        refused(inst, inst.get_int64([vr])[0], n, "fmi3GetInt64", f"value reference {vr}")
        n = len(inst.log)
        refused(inst, inst.set_int64([vr], [1]), n, "fmi3SetInt64", f"value reference {vr}")
    n = len(inst.log)
    refused(inst, inst.set_int64([free_lib.info.int64_vrs["method"]], [99]), n, "method 99", "allowed: 1=rk4")
    n = len(inst.log)
    refused(inst, inst.set_float64([1], [1.0], n_values=2), n, "nValues (2) must equal nValueReferences (1)")
    assert inst.do_step(0.0, 1e-3)[0] == OK
    inst.free()


def test_outputs_and_time_are_not_settable(free_lib):
    inst = in_state(free_lib, INST)
    for name, what in (
        ("time", "independent variable"),
        ("E_kin", "calculated output"),
        ("der(w_body[1])", "state derivative"),
    ):
        if name not in free_lib.info.vr:
            continue
        n = len(inst.log)
        refused(inst, inst.set_float64([free_lib.info.vr[name]], [1.0]), n, f"'{name}'", what)
    inst.free()


# ---- instantiation ----


def test_wrong_token_returns_null_and_names_both_tokens(free_lib):
    for me in (False, True):
        inst = free_lib.instantiate(token="{00000000-0000-0000-0000-000000000000}", model_exchange=me)
        assert inst.handle is None
        text = "\n".join(inst.errors_since(0))
        assert "'{00000000-0000-0000-0000-000000000000}' does not match" in text and free_lib.info.token in text


@pytest.mark.parametrize("name", ["", None])
def test_empty_instance_name_returns_null(free_lib, name):
    inst = free_lib.instantiate(name=name)
    assert inst.handle is None and "instanceName must be a non-empty string" in "\n".join(inst.errors_since(0))


def test_event_mode_requested_returns_null(free_lib):
    inst = free_lib.instantiate(event_mode_used=True)
    assert inst.handle is None and "eventModeUsed=true" in "\n".join(inst.errors_since(0))


def test_refused_instantiation_without_logger_does_not_crash(free_lib):
    """logMessage = NULL: the refusal cannot be logged, but must not dereference it."""
    null_logger = LOG_CALLBACK()  # a NULL function pointer
    assert (
        free_lib.InstantiateCoSimulation(
            b"x", b"{bad}", None, False, True, False, False, None, 0, None, null_logger, None
        )
        is None
    )
    assert (
        free_lib.InstantiateCoSimulation(
            b"", free_lib.info.token.encode(), None, False, True, False, False, None, 0, None, null_logger, None
        )
        is None
    )


# ---- the start quaternion ----


@pytest.mark.parametrize(
    "q", [(1.1, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 2e-3), (1.0 + 2e-6, 0.0, 0.0, 0.0)]
)
def test_start_quaternion_far_from_unit_refused(free_lib, q):
    inst = in_state(free_lib, INIT)
    assert inst.set_float64([free_lib.info.vr[f"q[{k}]"] for k in range(1, 5)], list(q)) == OK
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, "quaternion q must have unit norm", "1e-06")
    inst.free()


def test_start_quaternion_refusal_names_its_norm(free_lib):
    inst = in_state(free_lib, INIT)
    assert inst.set_float64([free_lib.info.vr["q[1]"]], [1.1]) == OK
    n = len(inst.log)
    text = refused(inst, inst.exit_initialization_mode(), n, "quaternion")
    assert "1.1" in text  # |q| = 1.1 or q[1]=1.1
    inst.free()


@pytest.mark.parametrize("scale", [1 + 5e-7, 1 - 5e-7, 1 + 9.9e-7])
def test_start_quaternion_within_tolerance_is_normalised(free_lib, scale):
    """| |q| - 1 | <= 1e-6 is accepted and normalised: |q| = 1 to round-off (a few ulp of
    the division q/|q|), the direction unchanged."""
    u = np.array([0.5, 0.5, 0.5, -0.5])
    vrs = [free_lib.info.vr[f"q[{k}]"] for k in range(1, 5)]
    inst = in_state(free_lib, INIT)
    assert inst.set_float64(vrs, list(u * scale)) == OK
    assert inst.exit_initialization_mode() == OK, inst.log
    q = np.array(inst.get_float64(vrs)[1])
    assert abs(np.linalg.norm(q) - 1.0) <= 2 * np.finfo(float).eps
    assert np.max(np.abs(q - u)) <= 2 * np.finfo(float).eps
    inst.free()


# ---- two instances, FMU state across interface types ----


def test_instances_are_independent(free_lib):
    """Two instances stepped interleaved give bit-identical results to each run alone."""
    vr = free_lib.info.vr
    names = ["q[1]", "q[2]", "q[3]", "q[4]", "w_body[1]", "w_body[2]", "w_body[3]"]

    def start(w):
        inst = free_lib.instantiate()
        assert inst.set_float64([vr["w_body[1]"], vr["w_body[2]"]], [w, 1.0]) == OK
        assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
        return inst

    a, b = start(0.1), start(-0.3)
    for k in range(20):
        assert a.do_step(k * 1e-2, 1e-2)[0] == OK and b.do_step(k * 1e-2, 1e-2)[0] == OK
    got_a, got_b = a.get_float64([vr[n] for n in names])[1], b.get_float64([vr[n] for n in names])[1]
    a.free(), b.free()
    for w, got in ((0.1, got_a), (-0.3, got_b)):
        alone = start(w)
        for k in range(20):
            assert alone.do_step(k * 1e-2, 1e-2)[0] == OK
        assert alone.get_float64([vr[n] for n in names])[1] == got
        alone.free()


@pytest.mark.parametrize("source_me", [True, False], ids=["ME_into_CS", "CS_into_ME"])
def test_fmu_state_is_refused_by_an_instance_of_the_other_interface(free_lib, source_me):
    source = free_lib.instantiate(model_exchange=source_me)
    target = free_lib.instantiate(model_exchange=not source_me)
    for inst in (source, target):  # -> EventMode (ME) / StepMode (CS)
        assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    status, snapshot = source.get_fmu_state()
    assert status == OK
    n = len(target.log)
    status = target.set_fmu_state(snapshot)
    try:
        refused(target, status, n, "fmi3SetFMUState")
    finally:
        assert source.free_fmu_state(snapshot) == OK
        source.free(), target.free()


def test_fmu_state_round_trip_restores_the_run(free_lib):
    """Get the state, step, restore, step again: bit-identical; a serialized copy
    restores into another instance; corrupted bytes are refused with a message."""
    vr = free_lib.info.vr
    names = [vr[n] for n in ("time", "q[1]", "q[4]", "w_body[1]", "w_body[2]")]
    inst = in_state(free_lib, INST)
    assert inst.set_float64([vr["w_body[1]"]], [0.3]) == OK
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    status, snap = inst.get_fmu_state()
    assert status == OK
    for k in range(5):
        assert inst.do_step(k * 1e-2, 1e-2)[0] == OK
    first = inst.get_float64(names)[1]
    assert inst.set_fmu_state(snap) == OK
    for k in range(5):
        assert inst.do_step(k * 1e-2, 1e-2)[0] == OK
    assert inst.get_float64(names)[1] == first
    status, size = inst.serialized_size(snap)
    status, data = inst.serialize(snap, size)
    assert status == OK
    other = in_state(free_lib, STEP)
    status, copy = other.deserialize(data)
    assert status == OK and other.set_fmu_state(copy) == OK
    for k in range(5):
        assert other.do_step(k * 1e-2, 1e-2)[0] == OK
    assert other.get_float64(names)[1] == first
    n = len(other.log)
    status, bad = other.deserialize(data[:-1])
    refused(other, status, n, "fmi3DeserializeFMUState", f"{size - 1} bytes")
    for i, s in ((inst, snap), (other, copy)):
        assert i.free_fmu_state(s) == OK and s.value is None
        i.free()


# ---- outputs follow the start values during initialisation ----


def test_outputs_in_initialization_mode_follow_the_start_values(free_lib):
    vr = free_lib.info.vr
    inst = in_state(free_lib, INIT)
    assert inst.set_float64([vr["w_body[1]"], vr["w_body[2]"], vr["w_body[3]"]], [2.0, -1.0, 0.5]) == OK
    # E = (I1 w1^2 + I2 w2^2 + I3 w3^2)/2 with I = (1, 2, 3): exact in binary floating point
    assert inst.get_float64([vr["E_kin"]]) == (OK, [0.5 * (4.0 + 2.0 + 0.75)])
    inst.free()


# ---- scene files (extends tests/test_bad_input.py) ----

GOOD = "[body]\nprincipal_moments = [1.0, 2.0, 3.0]\n[initial]\nw_body = [0.0, 1.0, 0.0]\n"
GRAVITY = (
    "[features]\ngravity = true\n[body]\nprincipal_moments = [1.0, 2.0, 3.0]\nmass = {m}\n"
    "[gravity]\nr_cm = [0.0, 0.0, 0.04]\ng = [0.0, 0.0, -9.81]\n[initial]\nw_body = [0.0, 0.0, 1.0]\n"
)


@pytest.mark.parametrize(
    "text, field, rule",
    [
        ("[body\nprincipal_moments = [1.0, 2.0, 3.0]\n", None, "not valid TOML"),
        ("colour = 'red'\n" + GOOD, "colour", "allowed top-level keys"),
        (GOOD.replace("[0.0, 1.0, 0.0]", "'fast'"), "initial.w_body", "must be a list of 3 numbers, got 'fast'"),
        (GOOD.replace("[0.0, 1.0, 0.0]", "[0.0, true, 0.0]"), "initial.w_body[2]", "must be a number, got True"),
        (
            GOOD + "q = [1.0, 0.0, 0.0, 0.0]\neuler_zxz = [0.0, 0.1, 0.0]\n",
            "initial",
            "at most one of 'q' and 'euler_zxz'",
        ),
        (
            GOOD + "q = [0.0, 0.0, 0.0, 0.0]\n",
            "initial.q",
            "must be a unit quaternion (|q| within 1e-06 of 1), got |q| = 0",
        ),
        (
            GOOD + "[experiment]\nmethods = ['rk4', 'gauss4']\nmethod = 'rk8'\n",
            "experiment.method",
            "must be one of the scene's methods rk4, gauss4, got 'rk8'",
        ),
        (GOOD + "[experiment]\nmethods = ['rk5']\n", "experiment.methods", "drawn from rk4, rk8"),
        (GOOD + "[experiment]\nh_max = 0.0\n", "experiment.h_max", "must be > 0, got 0.0"),
        (
            "[features]\ntorque_body = true\n"
            + GOOD
            + "[inputs]\ntau_body = [[0.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 0.0]]\n",
            "inputs.tau_body",
            "table times (first column) must increase strictly",
        ),
        (
            "[features]\ntorque_body = true\n"
            + GOOD
            + "[inputs]\ntau_body = [[0.0, 0.0, 1.0], [1.0, 1.0, 0.0, 0.0]]\n",
            "inputs.tau_body[1]",
            "must be a list of 4 numbers",
        ),
        ("name = 'my top'\n" + GOOD, "name", "must be an identifier"),
        (
            GOOD.replace(
                "principal_moments = [1.0, 2.0, 3.0]",
                "principal_moments = [1.0, 2.0, 3.0]\ninertia = [[1.0, 0, 0], [0, 2.0, 0], [0, 0, 3.0]]",
            ),
            "body",
            "give exactly one of 'principal_moments'",
        ),
        ("[features]\nfriction = true\n" + GOOD + "[friction]\nc = -1e-5\n", "friction.c", "must be >= 0, got -1e-05"),
        (GRAVITY.format(m=-0.5), "body.mass", "must be > 0, got -0.5"),
        (GRAVITY.format(m=0), "body.mass", "must be > 0, got 0.0"),
        (
            GOOD + "[gravity]\nr_cm = [0.0, 0.0, 0.04]\ng = [0.0, 0.0, -9.81]\n",
            "gravity",
            "given but features.gravity is not true",
        ),
        (
            GOOD.replace("principal_moments = [1.0, 2.0, 3.0]", "inertia = [[1.0, 0.1, 0], [0.1, 2.0, 0], [0, 0, 2.5]]")
            + "[experiment]\nmethods = ['splitting']\n",
            "experiment.methods",
            "splitting and exact_free need principal axes",
        ),
        ("outputs = ['q', 'energy']\n" + GOOD, "outputs", "must be a list drawn from q, w_body"),
        ("features = 'gravity'\n" + GOOD, "features", "must be a table [features]"),
    ],
)
def test_malformed_scene_names_file_field_and_rule(tmp_path, text, field, rule):
    path = write_scene(tmp_path, text)
    with pytest.raises(ModelInputError) as exc:
        load_scene(path)
    msg = str(exc.value)
    assert str(path) in msg and rule in msg, msg
    if field:
        assert f"field '{field}'" in msg, msg


def test_set_int64_is_all_or_nothing(free_lib):
    """SetInt64 with one invalid entry changes nothing, also when an earlier entry was valid."""
    vr = free_lib.info.vr["method"]
    inst = in_state(free_lib, INIT)
    before = inst.get_int64([vr])[1]
    n = len(inst.log)
    refused(inst, inst.set_int64([vr, vr], [4, 99]), n, "fmi3SetInt64", "method 99 is not compiled")
    assert inst.get_int64([vr])[1] == before
    inst.free()
