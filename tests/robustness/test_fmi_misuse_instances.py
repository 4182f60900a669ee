"""FMI misuse, second part: unknown references, refused instantiation, start quaternions, instances and FMU states.

The conventions of tests/robustness/test_fmi_misuse.py: every refusal is fmi3Error plus a logged
message naming the function and the offending value; the instance stays consistent.
"""

from __future__ import annotations

import numpy as np
import pytest

from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene

from ..harness.fmi3_ctypes import LOG_CALLBACK, OK
from ..harness.misuse_helpers import INIT, INST, STEP, in_state, refused
from ..harness.scenes import write_scene


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
    status, _bad = other.deserialize(data[:-1])
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


# ---- scene files (extends tests/robustness/test_bad_input.py) ----

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
        (GOOD + "[experiment]\nh_max = -1.0\n", "experiment.h_max", "must be >= 0, got -1.0"),
        (GOOD + "[experiment]\ntolerance = -1e-9\n", "experiment.tolerance", "must be >= 0, got -1e-09"),
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
        ("name = 'my top'\n" + GOOD, "name", "must be an ASCII identifier"),
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
