"""Inputs that vary inside a communication step through FMI 2.0 input derivatives: accuracy, clearing, bad input.

The torque_driven body (I = diag(1, 2, 3) kg·m², from rest) is driven by a body-frame torque
that is a cubic polynomial in time (CubicTorque). Given its value and three derivatives at
each communication point (fmi2SetRealInputDerivatives), the FMU has the exact torque inside
every step, so the error is the integrator's alone and falls with the method's order; held
inputs leave a first-order error in the communication step Δ whatever the method
(docs/fmi_layer.md, Inputs inside a step). Reference: scipy DOP853 at rtol 1e-13 on rbcheck's
independent right-hand side with the exact torque (rbcheck.workprecision.forced_inputs).
FMI 3.0 intermediate update: tests/fmi/test_inputs_inside_step_fmi3.py.
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from modelsrc.methods import METHODS
from rbcheck.workprecision.forced_inputs import observed_order, reference, run_fmu

from ..harness.fmi2_slave import TAU, Slave2

T_END = 2.0  # s
EVERY = 0.1  # s: the check times (multiples of every Δ below)
STEPS = (0.05, 0.025, 0.0125)  # s: one fixed internal step per communication step (h_max = Δ)
W = ["w_body[1]", "w_body[2]", "w_body[3]"]


class CubicTorque:
    """tau_body(t) = C @ (1, t, t², t³) (N·m, body frame; t in s): exactly a cubic, so its value
    and first three derivatives at the start of a step describe it over the whole step."""

    C = np.array([[0.1, 0.4, -0.3, 0.05], [0.0, -0.2, 0.5, -0.1], [0.3, 0.1, 0.0, -0.04]])

    def derivative(self, t: float, order: int) -> np.ndarray:
        """d^order tau / dt^order at t (N·m/s^order), order 0..3."""
        powers = [math.perm(j, order) * t ** (j - order) if j >= order else 0.0 for j in range(4)]
        return self.C @ np.array(powers)

    def __call__(self, t: float) -> np.ndarray:
        return self.derivative(t, 0)


@pytest.fixture(scope="module")
def ref() -> np.ndarray:
    return reference(CubicTorque(), np.arange(round(T_END / EVERY) + 1) * EVERY)


def _errors(Y: np.ndarray, ref: np.ndarray) -> float:
    """Largest |ω − ω_ref| (rad/s) over the check times, relative to max |ω_ref|."""
    return float(np.max(np.linalg.norm(Y[:, 4:7] - ref[:, 4:7], axis=1)) / np.max(np.linalg.norm(ref[:, 4:7], axis=1)))


def _fixed(method: str, dt: float) -> dict[str, float]:
    return {"tolerance": 0.0, "h_max": dt, "method": METHODS[method].value}


def test_fmi2_model_description_declares_interpolation(torque_driven_fmi2):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    assert not validate_fmu(str(torque_driven_fmi2))  # the attributes are valid FMI 2.0 (schema)
    md = read_model_description(str(torque_driven_fmi2))
    assert md.coSimulation.canInterpolateInputs is True
    assert md.coSimulation.maxOutputDerivativeOrder == 2


# (method, its order): the cubic torque is exact at every node, so the error is the method's
# own, C Δ^p. Bands: the slopes measured are within 0.02 of p at these steps (the asymptotic
# regime: |ω| Δ ≤ 0.05 rad), ±0.3 leaves room for the next term of the error expansion
# without admitting the next lower order.
@pytest.mark.parametrize("method, order", [("rk4", 4), ("gauss4", 4), ("splitting", 2)])
def test_polynomial_torque_is_integrated_to_the_method_order(torque_driven_fmi2, ref, method, order):
    held, interpolated = [], []
    for dt in STEPS:
        for mode, out in (("held", held), ("fmi2_derivatives", interpolated)):
            _, Y, _, _ = run_fmu(torque_driven_fmi2, mode, dt, T_END, CubicTorque(), _fixed(method, dt), EVERY)
            out.append(_errors(Y, ref))
    p_held, p_interp = observed_order(STEPS, held), observed_order(STEPS, interpolated)
    # held: the torque's first-order hold error, τ̇ Δ/2 per step, dominates every method
    assert p_held == pytest.approx(1.0, abs=0.1), held
    assert p_interp == pytest.approx(order, abs=0.3), interpolated
    assert interpolated[-1] < 1e-2 * held[-1], (held, interpolated)


def test_default_error_control_meets_its_tolerance_with_input_derivatives(torque_driven_fmi2, ref):
    # the FMU's defaults (rk8, tolerance 1e-10 per second of simulated time, docs/theory.md
    # §5.5) promise about tolerance·T = 2e-10 at T = 2 s; held inputs stay at the hold error
    dt = 0.05
    _, Y, _, _ = run_fmu(torque_driven_fmi2, "fmi2_derivatives", dt, T_END, CubicTorque(), None, EVERY)
    e_interp = _errors(Y, ref)
    _, Y, _, _ = run_fmu(torque_driven_fmi2, "held", dt, T_END, CubicTorque(), None, EVERY)
    e_held = _errors(Y, ref)
    assert e_interp <= 1e-10 * T_END, e_interp
    assert e_held > 1e-3, e_held  # τ̇ Δ/2 ≈ 0.01 N·m of torque error per step


# ---- the FMI 2.0 calls themselves, through fmpy with a logger that keeps the messages ----


@pytest.fixture
def slave2(torque_driven_fmi2):
    made: list[Slave2] = []

    def make(start: dict[str, float] | None = None) -> Slave2:
        made.append(Slave2(torque_driven_fmi2, start))
        return made[-1]

    Slave2.messages.clear()
    yield make
    for s in made:
        s.close()


def test_derivatives_belong_to_one_doStep(slave2):
    # both instances take the same first step with input derivatives; in the second, A sets
    # none and B sets them to zero explicitly: A must hold its inputs again, bit for bit as B
    tq = CubicTorque()
    a, b = slave2(), slave2()
    derivs = [tq.derivative(0.0, k) for k in (1, 2, 3)]
    for s in (a, b):
        s.step(0.1, tq(0.0), derivs)
    b.s.setRealInputDerivatives(b.names(TAU * 3), [1, 1, 1, 2, 2, 2, 3, 3, 3], [0.0] * 9)
    a.step(0.1, tq(0.1))
    b.step(0.1, tq(0.1))
    assert np.array_equal(a.get(W + ["q[1]"]), b.get(W + ["q[1]"]))


def test_inputs_after_a_polynomial_step_are_its_end_value(slave2):
    # the outputs at t + Δ are computed with the inputs there: the polynomial's value at Δ
    # (a cubic in Δ evaluated in double precision: a few ulps of |τ| ≈ 0.5 N·m)
    tq = CubicTorque()
    s = slave2()
    s.s.setReal(s.names(TAU), [float(v) for v in tq(0.0)])
    for order in (1, 2, 3):
        s.s.setRealInputDerivatives(s.names(TAU), [order] * 3, [float(v) for v in tq.derivative(0.0, order)])
    s.s.doStep(0.0, 0.3)
    assert s.get(TAU) == pytest.approx(tq(0.3), rel=0, abs=1e-15)


def test_a_polynomial_step_can_be_repeated_from_a_saved_state(slave2):
    # the derivatives are part of the step's inputs, not of the FMU state: set again after
    # SetFMUstate they reproduce the step bit for bit
    tq = CubicTorque()
    s = slave2()
    state = s.s.getFMUstate()
    results = []
    for _ in range(2):
        s.s.setFMUstate(state)
        s.t = 0.0
        s.step(0.2, tq(0.0), [tq.derivative(0.0, k) for k in (1, 2, 3)])
        results.append(s.get(W))
    s.s.freeFMUstate(state)
    assert np.array_equal(results[0], results[1])


BAD_DERIVATIVES = [
    ([8], [1], [math.nan], "derivative 1 of 'tau_body[1]' must be finite, got nan"),
    ([9], [2], [math.inf], "derivative 2 of 'tau_body[2]' must be finite, got inf"),
    ([8], [0], [1.0], "derivative order 0 of 'tau_body[1]' is not 1..3"),
    ([10], [4], [1.0], "derivative order 4 of 'tau_body[3]' is not 1..3"),
    ([5], [1], [1.0], "value reference 5 is not an input (inputs: 8..13)"),  # w_body[1]: a state
    ([99999], [1], [1.0], "value reference 99999 is not an input"),
]


@pytest.mark.parametrize("vrs, orders, values, message", BAD_DERIVATIVES)
def test_bad_input_derivatives_are_refused_and_change_nothing(slave2, vrs, orders, values, message):
    from fmpy.fmi1 import FMICallException

    tq = CubicTorque()
    s, held = slave2(), slave2()
    assert s.vr["tau_body[1]"] == 8 and s.vr["w_body[1]"] == 5  # the value references named above
    s.s.setReal(s.names(TAU), [float(v) for v in tq(0.0)])
    # all-or-nothing: a valid derivative ahead of the bad one is not kept either
    with pytest.raises(FMICallException):
        s.s.setRealInputDerivatives([9, *vrs], [1, *orders], [5.0, *values])
    assert any(message in m and "fmi2SetRealInputDerivatives" in m for m in s.messages), s.messages
    s.s.doStep(0.0, 0.1)
    held.step(0.1, tq(0.0))
    assert np.array_equal(s.get(W), held.get(W))


def test_input_derivatives_are_refused_where_the_state_forbids_them(slave2, torque_driven_fmi2):
    import ctypes as C

    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Model

    s = slave2()
    s.s.terminate()
    with pytest.raises(FMICallException):
        s.s.setRealInputDerivatives([8], [1], [1.0])
    assert any("fmi2SetRealInputDerivatives: not allowed in state Terminated" in m for m in s.messages), s.messages
    # a Model Exchange instance of the same FMU: the importer's solver sees u(t) itself
    md = read_model_description(str(torque_driven_fmi2))
    unzip = extract(str(torque_driven_fmi2))
    me = FMU2Model(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.modelExchange.modelIdentifier)
    me.instantiate(callbacks=Slave2._callbacks)
    me.setupExperiment(startTime=0.0)
    me.enterInitializationMode()
    fn = me.dll.fmi2SetRealInputDerivatives  # fmpy wraps it for Co-Simulation only
    fn.argtypes = [C.c_void_p, C.POINTER(C.c_uint), C.c_size_t, C.POINTER(C.c_int), C.POINTER(C.c_double)]
    status = fn(me.component, (C.c_uint * 1)(8), 1, (C.c_int * 1)(1), (C.c_double * 1)(1.0))
    assert status == 3  # fmi2Error
    me.freeInstance()
    shutil.rmtree(unzip, ignore_errors=True)
    assert any("input derivatives are a Co-Simulation call" in m for m in Slave2.messages), Slave2.messages


def test_the_report_section_measures_hold_against_interpolation(fmus, torque_driven_fmi2):
    # the report's part "inputs" (rbcheck.workprecision.forced_inputs) on a short ladder:
    # tau = (a sin² t, b cos t, c) with the FMU's defaults. Held: first order in Δ; the cubic
    # Taylor polynomial of FMI 2.0: O(Δ⁴) (slopes measured 1.00 and 4.01 on this ladder, bands
    # as above); FMI 3.0 intermediate update: the error control's tolerance·T, whatever Δ
    from rbcheck.workprecision.forced_inputs import MODE_TITLES, measure_forced_inputs, write_forced_inputs

    steps = (0.1, 0.05, 0.025)
    res = measure_forced_inputs(fmus["torque_driven"], torque_driven_fmi2, steps, stop_time=1.0)
    assert observed_order(steps, res.e_w["held"]) == pytest.approx(1.0, abs=0.1), res.e_w
    assert observed_order(steps, res.e_w["fmi2_derivatives"]) == pytest.approx(4.0, abs=0.3), res.e_w
    assert max(res.e_w["fmi3_intermediate"] + res.e_R["fmi3_intermediate"]) <= 1e-10 * 1.0, res.e_w
    lines: list[str] = []
    write_forced_inputs(lines.append, res)
    text = "\n".join(lines)
    assert "## Inputs inside a communication step" in text
    assert all(title in text for title in MODE_TITLES.values())
    assert sum(line.startswith(f"| {dt:g} |") for dt in steps for line in lines) == len(steps)
