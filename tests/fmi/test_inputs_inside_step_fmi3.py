"""Inputs that vary inside a communication step through FMI 3.0 intermediate update: node times, accuracy, rules.

An importer that passes an intermediateUpdate callback and names the inputs it will set
(requiredIntermediateVariables) is called at the FMU's internal node times t + c_k h
(docs/fmi_layer.md, Inputs inside a step) in IntermediateUpdateMode, where it may set inputs
and nothing else (docs/fmi_layer.md §3; tests/harness/fuzz_fmi_model.py is the independent model of
that state's row, checked here call by call). A torque evaluated exactly in the callback is
then integrated to the method's accuracy; without a callback the inputs are held.
"""

from __future__ import annotations

import ctypes as C
import math

import numpy as np
import pytest

from modelsrc.methods import METHODS
from rbcheck.workprecision.forced_inputs import SmoothTorque, observed_order, reference, run_fmu

from ..harness import fuzz_fmi_model as spec
from ..harness.fmi3_ctypes import OK, Fmi3Instance, Fmi3Library, extract_fmu

TAU = ["tau_body[1]", "tau_body[2]", "tau_body[3]"]
W = ["w_body[1]", "w_body[2]", "w_body[3]"]
Q = ["q[1]", "q[2]", "q[3]", "q[4]"]
IUM = spec.IUM


@pytest.fixture(scope="module")
def fmu3(fmus):
    return fmus["torque_driven"]


@pytest.fixture(scope="module")
def lib(fmu3, tmp_path_factory) -> Fmi3Library:
    return Fmi3Library(extract_fmu(fmu3, tmp_path_factory.mktemp("torque_driven_fmi3")))


def start(lib: Fmi3Library, update=None, required=(), values: dict[str, float] | None = None) -> Fmi3Instance:
    """A Co-Simulation instance in StepMode at t = 0 with start values (method by name)."""
    inst = lib.instantiate(intermediate_update=update, required=required)
    assert inst.handle, inst.log
    values = dict(values or {})
    method = values.pop("method", None)
    if method is not None:
        assert inst.set_int64([lib.info.int64_vrs["method"]], [METHODS[method].value]) == OK
    assert inst.set_float64([lib.info.vr[n] for n in values], list(values.values())) == OK
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK, inst.log
    return inst


def test_fmi3_model_description_declares_intermediate_update(lib):
    from fmpy.validation import validate_fmu

    info = lib.info
    assert info.cs_flags["providesIntermediateUpdate"] == "true"
    assert info.cs_flags["canReturnEarlyAfterIntermediateUpdate"] == "false"
    assert info.cs_flags["maxOutputDerivativeOrder"] == "2"
    from xml.etree import ElementTree

    root = ElementTree.parse(lib.unzipdir / "modelDescription.xml").getroot()
    flagged = {v.get("name") for v in root.find("ModelVariables") if v.get("intermediateUpdate") == "true"}
    assert flagged == {n for n, c in info.causality.items() if c == "input"}  # every input, nothing else
    assert not validate_fmu(str(lib.unzipdir))


def _dop853_nodes() -> list[float]:
    from scipy.integrate._ivp import dop853_coefficients as dop

    return sorted({float(c) for c in dop.C[: dop.N_STAGES] if c > 0} | {1.0})


# The nodes c_k in (0, 1] at which each method reads its inputs: the stage abscissae of its
# tableau (rk4: HNW I §II.1; DOP853: HNW I §II.10; Gauss: the roots of the shifted Legendre
# polynomials, HW II §IV.5) and the step's end; node 0 is the step's start, set before.
NODES = {
    "rk4": [0.5, 1.0],
    "gauss4": [0.5 - math.sqrt(3) / 6, 0.5 + math.sqrt(3) / 6, 1.0],
    "gauss6": [0.5 - math.sqrt(15) / 10, 0.5, 0.5 + math.sqrt(15) / 10, 1.0],
    "splitting": [1.0],  # a torque kick at each end of the step
    "rk8": _dop853_nodes(),
}


@pytest.mark.parametrize("method", sorted(NODES))
def test_the_importer_is_asked_at_the_method_nodes(lib, method):
    times: list[float] = []
    inst = start(lib, times.append, [lib.info.vr[n] for n in TAU], {"method": method, "tolerance": 0.0, "h_max": 0.05})
    assert inst.do_step(0.0, 0.1) == (OK, 0.1)  # two fixed internal steps of 0.05 s
    want = [0.05 * (k + c) for k in (0, 1) for c in NODES[method]]
    # node times t0 + tau + c h in double precision: within a few ulps of 0.1
    assert times == pytest.approx(want, rel=0, abs=1e-16), (times, want)
    assert times[-1] == 0.1  # the last node is the communication point itself
    # intermediateVariableSetRequested, no gets, the step may still be redone, no early return
    assert inst.update_flags == (True, False, False, False)
    inst.free()


@pytest.mark.parametrize("method", ["rk8", "gauss4"])
def test_with_error_control_the_nodes_stay_inside_the_step_and_end_on_it(lib, method):
    times: list[float] = []
    inst = start(lib, times.append, [lib.info.vr[n] for n in TAU], {"method": method, "tolerance": 1e-12})
    t = 0.0
    for _ in range(3):
        n = len(times)
        assert inst.do_step(t, 0.25)[0] == OK, inst.log
        inside = times[n:]
        assert inside and all(t < s <= t + 0.25 for s in inside), inside
        assert inside[-1] == t + 0.25
        t += 0.25
    inst.free()


@pytest.mark.parametrize("with_callback", [False, True])
def test_without_a_callback_or_required_inputs_the_inputs_are_held(lib, with_callback):
    # NULL callback, or a callback with no requiredIntermediateVariables: never called, and the
    # run is bit for bit the held one; a callback that is asked but sets nothing holds too
    calls: list[float] = []
    fixed = {"method": "rk4", "tolerance": 0.0, "h_max": 0.02}
    held = start(lib, None, (), fixed)
    quiet = start(lib, calls.append if with_callback else None, (), fixed)
    idle = start(lib, lambda t: None, [lib.info.vr[n] for n in TAU], fixed)
    tau = [0.3, -0.2, 0.1]
    for inst in (held, quiet, idle):
        assert inst.set_float64([lib.info.vr[n] for n in TAU], tau) == OK
        assert inst.do_step(0.0, 0.1)[0] == OK
    assert not calls
    vrs = [lib.info.vr[n] for n in Q + W]
    assert held.get_float64(vrs) == quiet.get_float64(vrs) == idle.get_float64(vrs)
    for inst in (held, quiet, idle):
        inst.free()


def test_inputs_after_the_doStep_are_the_last_ones_set(lib):
    tq = SmoothTorque()
    vrs = [lib.info.vr[n] for n in TAU]
    holder: list[Fmi3Instance] = []
    inst = start(lib, lambda t: holder[0].set_float64(vrs, list(tq(t))), vrs, {"method": "rk4"})
    holder.append(inst)
    assert inst.do_step(0.0, 0.3)[0] == OK
    assert inst.get_float64(vrs)[1] == list(tq(0.3))  # set at the node t = 0.3 exactly
    inst.free()


def test_required_intermediate_variables_must_be_inputs(lib):
    inst = lib.instantiate(intermediate_update=lambda t: None, required=[lib.info.vr["w_body[1]"]])
    assert not inst.handle
    assert any(
        "requiredIntermediateVariables names value reference 5, which is not an input" in m for _, _, m in inst.log
    ), inst.log


def _errors(Y: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.linalg.norm(Y[:, 4:7] - ref[:, 4:7], axis=1)) / np.max(np.linalg.norm(ref[:, 4:7], axis=1)))


def test_a_smooth_torque_is_integrated_to_the_method_order(fmu3):
    # tau = (a sin² t, b cos t, c) evaluated exactly at every node: rk4 with one fixed
    # internal step per communication step has its own error C Δ⁴; held, the error is
    # first order in Δ. Bands as in tests/fmi/test_inputs_inside_step_fmi2.py (slopes measured
    # within 0.02 of 4 and 1 at these steps).
    tq, steps, T = SmoothTorque(), (0.05, 0.025, 0.0125), 2.0
    ref = reference(tq, np.arange(21) * 0.1)
    held, asked = [], []
    for dt in steps:
        fixed = {"tolerance": 0.0, "h_max": dt, "method": METHODS["rk4"].value}
        for mode, out in (("held", held), ("fmi3_intermediate", asked)):
            out.append(_errors(run_fmu(fmu3, mode, dt, T, tq, fixed, 0.1)[1], ref))
    assert observed_order(steps, held) == pytest.approx(1.0, abs=0.1), held
    assert observed_order(steps, asked) == pytest.approx(4.0, abs=0.3), asked
    # the defaults (rk8, error control at 1e-10 per second, docs/theory.md §5.5): within
    # tolerance·T at any communication step, where held inputs are three orders off
    for dt in (0.1, 0.02):
        e = _errors(run_fmu(fmu3, "fmi3_intermediate", dt, T, tq, None, 0.1)[1], ref)
        assert e <= 1e-10 * T, (dt, e)
    assert held[-1] > 1e-3


# ---- IntermediateUpdateMode: every call of the fuzz model's table, made inside the callback ----


def _calls(inst: Fmi3Instance, info) -> dict[str, object]:
    """fmi3 function -> a call of it on inst returning its status (arguments that would be
    valid in a state that admits the call)."""
    n = C.c_size_t()
    x = [1.0, 0, 0, 0, 0, 0, 0]
    return {
        "fmi3EnterInitializationMode": lambda: inst.enter_initialization_mode(0.0),
        "fmi3ExitInitializationMode": inst.exit_initialization_mode,
        "fmi3SetFloat64": lambda: inst.set_float64([info.vr["tau_body[1]"]], [0.25]),
        "fmi3GetFloat64": lambda: inst.get_float64([info.vr["w_body[1]"]])[0],
        "fmi3SetInt64": lambda: inst.set_int64([info.int64_vrs["method"]], [METHODS["rk4"].value]),
        "fmi3GetInt64": lambda: inst.get_int64([info.int64_vrs["method"]])[0],
        "fmi3DoStep": lambda: inst.do_step(0.0, 0.01)[0],
        "fmi3Terminate": inst.terminate,
        "fmi3Reset": inst.reset,
        "fmi3SetDebugLogging": lambda: inst.set_debug_logging(False),
        "fmi3EnterEventMode": inst.enter_event_mode,
        "fmi3EnterStepMode": inst.enter_step_mode,
        "fmi3EnterContinuousTimeMode": inst.enter_continuous_time_mode,
        "fmi3CompletedIntegratorStep": inst.completed_integrator_step,
        "fmi3SetTime": lambda: inst.set_time(0.0),
        "fmi3SetContinuousStates": lambda: inst.set_continuous_states(x),
        "fmi3GetContinuousStates": lambda: inst.get_continuous_states(7)[0],
        "fmi3GetContinuousStateDerivatives": lambda: inst.get_derivatives(7)[0],
        "fmi3UpdateDiscreteStates": inst.update_discrete_states,
        "fmi3GetFMUState": lambda: inst.get_fmu_state()[0],
        "fmi3SetFMUState": lambda: inst.set_fmu_state(None),
        "fmi3FreeFMUState": lambda: inst.free_fmu_state(C.c_void_p()),
        "fmi3SerializedFMUStateSize": lambda: inst.serialized_size(None)[0],
        "fmi3SerializeFMUState": lambda: inst.serialize(None, 0)[0],
        "fmi3DeserializeFMUState": lambda: inst.deserialize(b"")[0],
        "fmi3GetNumberOfContinuousStates": lambda: inst.lib.GetNumberOfContinuousStates(inst.handle, C.byref(n)),
        "fmi3GetOutputDerivatives": lambda: inst.get_output_derivatives([info.vr["w_body[1]"]], [1])[0],
    }


def test_intermediate_update_mode_admits_what_the_fuzz_model_says(lib):
    info = lib.info
    seen: dict[str, int] = {}
    holder: list[Fmi3Instance] = []

    def update(t: float) -> None:
        if seen:  # one round of calls, at the first node
            return
        for fn, call in _calls(holder[0], info).items():
            seen[fn] = call()

    inst = start(lib, update, [info.vr[n] for n in TAU], {"method": "rk4", "tolerance": 0.0, "h_max": 0.1})
    holder.append(inst)
    assert inst.do_step(0.0, 0.1) == (OK, 0.1), inst.errors_since(0)
    assert set(seen) >= set(spec.ALLOWED), set(spec.ALLOWED) - set(seen)
    for fn, status in seen.items():
        allowed = IUM in spec.ALLOWED[fn] if fn in spec.ALLOWED else False  # output derivatives: not in IUM
        assert (status == OK) == allowed, (fn, status, allowed)
        if not allowed:
            assert any(f"{fn}: not allowed in state IntermediateUpdateMode" in m for _, _, m in inst.log), fn
    # back in StepMode after the callback: the calls refused inside are accepted again
    assert inst.get_float64([info.vr["w_body[1]"]])[0] == OK
    assert inst.get_output_derivatives([info.vr["w_body[1]"]], [1])[0] == OK
    inst.free()


def test_in_intermediate_update_mode_only_inputs_can_be_set(lib):
    # one variable of each kind, set inside the callback; the fuzz model's SETTABLE row decides
    info = lib.info
    kinds = {"input": "tau_body[2]", "state": "w_body[1]", "tunable": "h_max", "output": "E_kin",
             "independent": "time", "local": "internal_steps"}  # fmt: skip
    seen: dict[str, int] = {}
    holder: list[Fmi3Instance] = []

    def update(t: float) -> None:
        for kind, name in kinds.items():
            seen.setdefault(kind, holder[0].set_float64([info.vr[name]], [0.5]))

    inst = start(lib, update, [info.vr[n] for n in TAU], {"method": "rk4", "tolerance": 0.0, "h_max": 0.1})
    holder.append(inst)
    assert inst.do_step(0.0, 0.1)[0] == OK
    for kind, status in seen.items():
        assert (status == OK) == (IUM in spec.SETTABLE[kind]), (kind, status)
        if status != OK:
            assert any(f"'{kinds[kind]}'" in m and "IntermediateUpdateMode" in m for _, _, m in inst.log), kind
    assert inst.get_float64([info.vr["h_max"]])[1] == [0.1]  # refused sets changed nothing
    inst.free()
