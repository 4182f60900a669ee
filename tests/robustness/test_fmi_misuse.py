"""FMI misuse and bad input: every refusal is fmi3Error with a message naming the function and value.

The instance stays consistent after a refusal.

Deterministic companion of the fuzzer (tests/robustness/test_fuzz_fmi.py): the state table of
docs/fmi_layer.md cell by cell, then each kind of bad input once, through the raw
FMI 3.0 C API (tests/harness/fmi3_ctypes.py) so that statuses and log messages are seen as an
importer sees them. Scene-file errors extend tests/robustness/test_bad_input.py (not repeated).
"""

from __future__ import annotations

import math

import pytest

from ..harness.fmi3_ctypes import ERROR, OK
from ..harness.misuse_helpers import INIT, INST, STATES, STEP, TABLE, c17, call, in_state, refused


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


@pytest.mark.parametrize(
    "name, bad, rule", [("h_max", -1e-3, "h_max must be >= 0"), ("tolerance", -1e-8, "tolerance must be >= 0")]
)
def test_negative_step_controls(free_lib, name, bad, rule):
    vr = free_lib.info.vr[name]
    inst = in_state(free_lib, INIT)  # at initialisation
    assert inst.set_float64([vr], [bad]) == OK
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, rule, f"{name}={c17(bad)}")
    inst.free()
    inst = in_state(free_lib, STEP)  # in step mode (tunable): refused, old value kept
    n = len(inst.log)
    refused(inst, inst.set_float64([vr], [bad]), n, "fmi3SetFloat64", rule)
    assert inst.get_float64([vr]) == (OK, [free_lib.info.start[name]])
    assert inst.do_step(0.0, 1e-2)[0] == OK
    inst.free()


def test_h_max_zero_is_no_cap(free_lib):
    # h_max = 0: no cap (docs/theory.md §5.4): fixed steps take one step per doStep unless
    # the method's limits need more; the spin of 1 rad/s needs none at H = 0.01 s
    inst = in_state(free_lib, STEP)
    assert inst.set_float64([free_lib.info.vr["h_max"]], [0.0]) == OK
    assert inst.do_step(0.0, 1e-2)[0] == OK
    assert inst.get_float64([free_lib.info.vr["internal_steps"]]) == (OK, [1.0])
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


def test_step_over_the_work_limit_refused(free_lib):
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
        "(h_max 1e-12",
        "needs 1e+10 internal steps of method rk4 at 4 right-hand-side evaluations each: 4e+10 evaluations",
        "more than work_limit = 5e+07; raise the tunable parameter work_limit",
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
