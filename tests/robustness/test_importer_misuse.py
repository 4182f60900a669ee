"""Calls an importer gets wrong: NULL arrays and result pointers, a time that would overflow or stall (FMI 3.0, 2.0).

Each is refused with fmi3Error (fmi2Error) and a message naming the function and what is
NULL or wrong, where it used to crash or return OK; the instance stays usable. An
fmi3FreeInstance from the intermediate-update callback is deferred to the end of the running
doStep (it used to free the instance under it: a heap-use-after-free). FMU-state
pointers that are not the instance's own are in tests/robustness/test_fmu_state_integrity.py.
"""

from __future__ import annotations

import ctypes as C
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from xml.etree import ElementTree

import pytest

from ..harness.fmi2_slave import Slave2, logging_callbacks
from ..harness.fmi3_ctypes import ERROR, OK, Fmi3Instance, extract_fmu, shared_fmu
from ..harness.misuse_helpers import STEP, in_state, refused

VR = C.c_uint32 * 1


def _me_continuous(lib) -> Fmi3Instance:
    inst = lib.instantiate(model_exchange=True)
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    assert inst.enter_continuous_time_mode() == OK
    return inst


def _own_state(inst: Fmi3Instance) -> C.c_void_p:
    status, state = inst.get_fmu_state()
    assert status == OK
    return state


# (call, the instance it needs, the fragment naming what is NULL); `h` the instance handle
NULL_CALLS = {
    "GetFloat64 values": (lambda lib, i: lib.GetFloat64(i.handle, VR(0), 1, None, 1), STEP, "the value array is NULL"),
    "GetFloat64 vrs": (
        lambda lib, i: lib.GetFloat64(i.handle, None, 1, (C.c_double * 1)(), 1),
        STEP,
        "the value reference array is NULL",
    ),
    "SetFloat64 values": (lambda lib, i: lib.SetFloat64(i.handle, VR(8), 1, None, 1), STEP, "the value array is NULL"),
    "GetInt64 values": (
        lambda lib, i: lib.GetInt64(i.handle, VR(lib.info.int64_vrs["method"]), 1, None, 1),
        STEP,
        "values is NULL",
    ),
    "SetInt64 values": (
        lambda lib, i: lib.SetInt64(i.handle, VR(lib.info.int64_vrs["method"]), 1, None, 1),
        STEP,
        "values is NULL",
    ),
    "SerializedFMUStateSize size": (
        lambda lib, i: lib.SerializedFMUStateSize(i.handle, _own_state(i), None),
        STEP,
        "the pointer for the result is NULL",
    ),
    "GetNumberOfContinuousStates": (
        lambda lib, i: lib.GetNumberOfContinuousStates(i.handle, None),
        STEP,
        "the pointer for the result is NULL",
    ),
    "GetContinuousStates": (lambda lib, i: lib.GetContinuousStates(i.handle, None, 7), "me", "the array is NULL"),
    "SetContinuousStates": (lambda lib, i: lib.SetContinuousStates(i.handle, None, 7), "me", "the array is NULL"),
    "GetContinuousStateDerivatives": (
        lambda lib, i: lib.GetContinuousStateDerivatives(i.handle, None, 7),
        "me",
        "the array is NULL",
    ),
    "GetDirectionalDerivative sensitivity": (
        lambda lib, i: lib.GetDirectionalDerivative(i.handle, VR(1), 1, VR(1), 1, (C.c_double * 1)(1.0), 1, None, 1),
        "me",
        "sensitivity is NULL",
    ),
}


@pytest.mark.parametrize("case", list(NULL_CALLS))
def test_null_array_or_result_pointer_is_refused(free_lib, case):
    call, where, fragment = NULL_CALLS[case]
    inst = _me_continuous(free_lib) if where == "me" else in_state(free_lib, where)
    n = len(inst.log)
    refused(inst, call(free_lib, inst), n, "fmi3" + case.split()[0], fragment)
    assert inst.get_float64([0])[0] == OK  # still usable
    inst.free()


@pytest.mark.parametrize("q", [(0.0, 0.0, 0.0, 0.0), (1e200, 0.0, 0.0, 1e200)], ids=["zero", "overflowing"])
def test_model_exchange_quaternion_without_a_finite_normalisation_is_refused(free_lib, q):
    """The outputs use q/|q|: a q of norm 0 (or whose square overflows) gave NaN outputs;
    now SetContinuousStates refuses it and the states are unchanged."""
    inst = _me_continuous(free_lib)
    before = inst.get_continuous_states(7)
    n = len(inst.log)
    status = inst.set_continuous_states([*q, 0.1, 0.2, 1.0])
    refused(inst, status, n, "fmi3SetContinuousStates: state 'q[1]'", "has no finite projection")
    assert inst.get_continuous_states(7) == before
    inst.free()


def test_time_that_would_overflow_or_not_advance_is_refused(free_lib):
    """doStep from t = 1.5e308: by 1e308 the time would overflow to +inf, by 1e-3 it would
    not change (below the resolution of the time); both refused, the time unchanged. A step
    that advances the time from 1e20 (h_max 1e5, a body at rest) still runs."""
    vr = free_lib.info.vr
    inst = free_lib.instantiate()
    assert inst.enter_initialization_mode(1.5e308) == OK and inst.exit_initialization_mode() == OK
    for H, fragment in ((1e308, "= inf: the time overflows"), (1e-3, "below the resolution of the time")):
        n = len(inst.log)
        status, last = inst.do_step(1.5e308, H)
        refused(inst, status, n, "fmi3DoStep: currentCommunicationPoint 1.5e+308 + communicationStepSize", fragment)
        assert last == 1.5e308 and inst.get_float64([vr["time"]]) == (OK, [1.5e308])
    inst.free()
    inst = free_lib.instantiate()
    assert inst.set_float64([vr["w_body[3]"], vr["h_max"]], [0.0, 1e5]) == OK
    assert inst.enter_initialization_mode(1e20) == OK and inst.exit_initialization_mode() == OK
    n = len(inst.log)
    refused(inst, inst.do_step(1e20, 1e-6)[0], n, "below the resolution of the time")
    assert inst.do_step(1e20, 1e5) == (OK, 1e20 + 1e5)
    inst.free()


# ---- FMI 2.0: the same core; its own adapters for Integer access, the no-variable types and the state size ----


@pytest.fixture(scope="module")
def fmi2_lib(tmp_path_factory):
    """The extreme_free FMU built for FMI 2.0, loaded, with typed functions and the
    process's logger whose variadic messages fmpy's native proxy formats (fmi2_slave)."""
    from fmu.build.build_fmu import build_fmu
    from modelsrc.scene import load_scene

    from ..harness.fmi3_ctypes import EXTREME_FREE_TOML

    out = tmp_path_factory.mktemp("fmi2")
    (out / "extreme_free.toml").write_text(EXTREME_FREE_TOML)
    unzipped = extract_fmu(build_fmu(load_scene(out / "extreme_free.toml"), out, fmi_version=2), out / "unzipped")
    dll = C.CDLL(str(unzipped / "binaries" / "linux64" / "extreme_free.so"))
    callbacks, messages = logging_callbacks(), Slave2.messages
    dll.fmi2Instantiate.restype = C.c_void_p
    dll.fmi2Instantiate.argtypes = [C.c_char_p, C.c_int, C.c_char_p, C.c_char_p, C.c_void_p, C.c_int, C.c_int]
    guid = ElementTree.parse(unzipped / "modelDescription.xml").getroot().get("guid")
    return dll, callbacks, messages, guid.encode()


FMI2_NULL_CALLS = {
    "fmi2GetReal": (lambda d, c: d.fmi2GetReal(c, VR(0), C.c_size_t(1), None), "the value array is NULL"),
    "fmi2SetReal": (
        lambda d, c: d.fmi2SetReal(c, None, C.c_size_t(1), (C.c_double * 1)(0.0)),
        "the value reference array is NULL",
    ),
    "fmi2GetInteger": (lambda d, c: d.fmi2GetInteger(c, VR(0), C.c_size_t(1), None), "value is NULL"),
    "fmi2SetInteger": (lambda d, c: d.fmi2SetInteger(c, VR(0), C.c_size_t(1), None), "value is NULL"),
    "fmi2GetBoolean": (lambda d, c: d.fmi2GetBoolean(c, None, C.c_size_t(1), (C.c_int * 1)()), "vr is NULL"),
    "fmi2SerializedFMUstateSize": (
        lambda d, c: d.fmi2SerializedFMUstateSize(c, _fmi2_state(d, c), None),
        "the pointer for the result is NULL",
    ),
}


def _fmi2_state(dll, comp) -> C.c_void_p:
    state = C.c_void_p()
    assert dll.fmi2GetFMUstate(comp, C.byref(state)) == OK
    return state


@pytest.mark.slow
@pytest.mark.parametrize("fn", list(FMI2_NULL_CALLS))
def test_fmi2_null_array_or_result_pointer_is_refused(fmi2_lib, fn):
    dll, callbacks, messages, guid = fmi2_lib
    comp = dll.fmi2Instantiate(b"t", 1, guid, b"", C.byref(callbacks), 0, 0)
    assert comp, messages
    assert dll.fmi2SetupExperiment(C.c_void_p(comp), 0, C.c_double(0.0), C.c_double(0.0), 0, C.c_double(0.0)) == OK
    assert dll.fmi2EnterInitializationMode(C.c_void_p(comp)) == OK
    assert dll.fmi2ExitInitializationMode(C.c_void_p(comp)) == OK
    n = len(messages)
    call, fragment = FMI2_NULL_CALLS[fn]
    assert call(dll, C.c_void_p(comp)) == ERROR
    text = "\n".join(messages[n:])
    assert fn in text and fragment in text, messages[n:]
    value = (C.c_double * 1)()
    assert dll.fmi2GetReal(C.c_void_p(comp), VR(0), C.c_size_t(1), value) == OK and not math.isnan(value[0])
    dll.fmi2FreeInstance(C.c_void_p(comp))


# ---- fmi3FreeInstance inside the intermediate-update callback ------------------------------

# Run in a subprocess: before the fix the call freed the instance under the running doStep
# (a segfault in the plain build, heap-use-after-free under ASan), which must not take the
# test process with it.
_FREE_IN_CALLBACK = textwrap.dedent(
    """
    import sys
    from tests.harness.fmi3_ctypes import ERROR, OK, Fmi3Library, extract_fmu
    from pathlib import Path
    fmu = Path(sys.argv[1])
    lib = Fmi3Library(extract_fmu(fmu, Path(sys.argv[2])))
    calls = []
    holder = []
    def update(t):
        calls.append(t)
        if len(calls) == 1:
            lib.FreeInstance(holder[0].handle)
    tau = [lib.info.vr[n] for n in ("tau_body[1]", "tau_body[2]", "tau_body[3]")]
    inst = lib.instantiate(intermediate_update=update, required=tau)
    holder.append(inst)
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    state = inst.get_fmu_state()[1]  # left to the deferred free (LeakSanitizer would report it)
    status, last = inst.do_step(0.0, 0.1)
    assert status == ERROR, status
    assert len(calls) == 1, calls  # asked nothing after the free
    text = " ".join(m for _, _, m in inst.log)
    assert "fmi3FreeInstance: called in state IntermediateUpdateMode" in text, inst.log
    assert "freed when the running fmi3DoStep returns" in text, inst.log
    print("deferred free OK")
    """
)


def _run_free_in_callback(fmu, tmp_path, env=None) -> subprocess.CompletedProcess:
    env = dict(env or os.environ)
    env["PYTHONPATH"] = str(Path(__file__).resolve().parent.parent.parent)
    return subprocess.run(
        [sys.executable, "-c", _FREE_IN_CALLBACK, str(fmu), str(tmp_path / "unzipped")],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )


def test_free_instance_inside_the_callback_is_deferred_to_the_end_of_doStep(tmp_path):
    proc = _run_free_in_callback(shared_fmu("extreme_free"), tmp_path)
    assert proc.returncode == 0 and "deferred free OK" in proc.stdout, (proc.returncode, proc.stderr[-2000:])


@pytest.mark.sanitizer
def test_free_instance_inside_the_callback_under_asan(tmp_path):
    """The same under AddressSanitizer + UBSan with leak detection: no use after free, and
    the instance and its FMU state are freed (no leak through the FMU's code; the python
    interpreter's own blocks at exit make LeakSanitizer end the process nonzero, as in
    test_asan_fuzz)."""
    from .test_fuzz_fmi import SANITIZER_FAULTS, _fmu_frames, _leak_blocks, _sanitizer_available, _sanitizer_env

    why = _sanitizer_available()
    if why:
        pytest.skip(f"compiler lacks the sanitizers: {why}")
    proc = _run_free_in_callback(shared_fmu("extreme_free", sanitize=True), tmp_path, _sanitizer_env())
    faults = [f for f in SANITIZER_FAULTS if f in proc.stderr]
    assert not faults, proc.stderr[-3000:]
    assert not [b for b in _leak_blocks(proc.stderr) if _fmu_frames(b, "extreme_free.so")], proc.stderr[-3000:]
    assert "deferred free OK" in proc.stdout, (proc.returncode, proc.stderr[-3000:])
    assert proc.returncode == 0 or "ERROR: LeakSanitizer: detected memory leaks" in proc.stderr


# ---- NULL result pointers of the FMI 2.0 status getters -----------------------------------


def test_fmi2_status_getters_name_a_null_value_pointer(fmi2_fmus):
    slave = Slave2(fmi2_fmus["skewed_bar"])
    try:
        dll, comp = slave.s.dll, slave.s.component
        for fn, kind in (
            ("fmi2GetRealStatus", 2),  # fmi2LastSuccessfulTime: provided, so only the pointer is wrong
            ("fmi2GetStatus", 0),
            ("fmi2GetBooleanStatus", 4),
            ("fmi2GetIntegerStatus", 3),
            ("fmi2GetStringStatus", 1),
        ):
            f = getattr(dll, fn)
            f.restype, f.argtypes = C.c_int, [C.c_void_p, C.c_int, C.c_void_p]
            n = len(Slave2.messages)
            assert f(comp, kind, None) == ERROR, fn
            text = " ".join(Slave2.messages[n:])
            assert f"{fn}: the pointer for the value (argument 'value') is NULL" in text, (fn, text)
            assert "not provided" not in text, (fn, text)
        value = C.c_double(-1.0)
        f = dll.fmi2GetRealStatus
        assert f(comp, 2, C.byref(value)) == OK and value.value == 0.0
    finally:
        slave.close()
