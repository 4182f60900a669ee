"""Output derivatives (fmi3GetOutputDerivatives, fmi2GetRealOutputDerivatives): closed forms, differences, refusals.

On torque_driven (I = diag(1, 2, 3) kg·m², body torque τ_b and world torque τ_w held) the
first derivatives have closed forms independent of the FMU's code: Euler's equations
ω̇ = I⁻¹(τ_b + Rᵀτ_w − ω × Iω) (docs/theory.md §2.1), q̇ = ½ q ⊗ (0, ω) (§1.2), the
angular-momentum balance L̇_world = R τ_b + τ_w and the power Ė = ω·(τ_b + Rᵀτ_w); the
second derivative of ω differentiates Euler's equations once more, with d(Rᵀτ_w)/dt =
−ω × Rᵀτ_w for a constant τ_w. Every output is also checked against central differences of
the FMU's own trajectory. The inputs' derivatives enter order 2 as set by the importer
(FMI 2.0 input derivatives; zero when held, and after a doStep, which clears them).
"""

from __future__ import annotations

import numpy as np
import pytest

from modelsrc.methods import METHODS
from rbcheck.numerics.rotation_np import quat_mul, quat_to_matrix

from ..harness.fmi2_slave import Slave2
from ..harness.fmi3_ctypes import ERROR, OK, Fmi3Library, extract_fmu

I = np.diag([1.0, 2.0, 3.0])
I_INV = np.linalg.inv(I)
TAU_B = np.array([0.3, -0.2, 0.1])  # N·m, body frame
TAU_W = np.array([0.0, 0.1, 0.05])  # N·m, world frame
SETTLE = 2.0  # s of driven motion before the derivatives are taken: ω and R generic
ACCURATE = {"method": "rk8", "tolerance": 1e-12}  # error control, docs/theory.md §5.5


def closed_forms(q: np.ndarray, w: np.ndarray, tau_dot_b: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """First derivatives of q, w_body, L_world, E_kin and the second of w_body at (q, ω)
    under TAU_B, TAU_W (held, or τ_b changing at tau_dot_b N·m/s)."""
    R = quat_to_matrix(q / np.linalg.norm(q))
    tau = TAU_B + R.T @ TAU_W
    w_dot = I_INV @ (tau - np.cross(w, I @ w))
    tau_dot = -np.cross(w, R.T @ TAU_W) + (tau_dot_b if tau_dot_b is not None else 0.0)
    w_ddot = I_INV @ (tau_dot - np.cross(w_dot, I @ w) - np.cross(w, I @ w_dot))
    return {
        "q": 0.5 * quat_mul(q, np.concatenate([[0.0], w])),
        "w_body": w_dot,
        "L_world": R @ TAU_B + TAU_W,
        "E_kin": np.array([w @ tau]),
        "w_body2": w_ddot,
    }


def _names(base: str, n: int) -> list[str]:
    return [f"{base}[{k}]" for k in range(1, n + 1)]


# ---- FMI 3.0 through ctypes ----


@pytest.fixture(scope="module")
def lib(fmus, tmp_path_factory) -> Fmi3Library:
    return Fmi3Library(extract_fmu(fmus["torque_driven"], tmp_path_factory.mktemp("outder")))


@pytest.fixture
def driven(lib):
    """An instance driven by TAU_B, TAU_W for SETTLE s (rk8, tolerance 1e-12)."""
    vr = lib.info.vr
    inst = lib.instantiate()
    assert inst.set_int64([lib.info.int64_vrs["method"]], [METHODS[ACCURATE["method"]].value]) == OK
    assert inst.set_float64([vr["tolerance"]], [ACCURATE["tolerance"]]) == OK
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
    taus = _names("tau_body", 3) + _names("tau_world", 3)
    assert inst.set_float64([vr[n] for n in taus], [*TAU_B, *TAU_W]) == OK
    assert inst.do_step(0.0, SETTLE)[0] == OK
    yield inst
    inst.free()


def test_first_and_second_derivatives_match_the_closed_forms(lib, driven):
    vr = lib.info.vr
    q = np.array(driven.get_float64([vr[n] for n in _names("q", 4)])[1])
    w = np.array(driven.get_float64([vr[n] for n in _names("w_body", 3)])[1])
    assert np.linalg.norm(w) > 0.3  # a generic state: every term of Euler's equations counts
    want = closed_forms(q, w)
    for name, n, order, key in [("q", 4, 1, "q"), ("w_body", 3, 1, "w_body"), ("L_world", 3, 1, "L_world"),
                                ("E_kin", 0, 1, "E_kin"), ("w_body", 3, 2, "w_body2")]:  # fmt: skip
        names = _names(name, n) if n else [name]
        status, got = driven.get_output_derivatives([vr[m] for m in names], [order] * len(names))
        assert status == OK, driven.errors_since(0)
        # both sides evaluate the same exact expressions in double precision: a few ulps of
        # the terms' size (|τ|, |ω|²|I| ≲ 1)
        assert np.asarray(got) == pytest.approx(want[key], rel=0, abs=1e-14), (name, order)


def test_every_output_derivative_matches_central_differences_of_the_trajectory(lib, driven):
    # y at t0, t0 + δ, t0 + 2δ from the FMU itself (rk8 at tolerance 1e-12), the derivative
    # read at t0 + δ. Central differences: truncation δ²/6 |y'''| resp. δ²/12 |y''''|
    # (≈ 2e-7 resp. 1e-7 with |y'''|, |y''''| ≲ 1 at δ = 1e-3), integration error ~1e-12·δ
    # over 2δ divided by δ resp. δ²: 1e-12 resp. 1e-9; round-off ε|y|/δ resp. 4ε|y|/δ² ≈
    # 2e-13 resp. 1e-9. Hence 1e-6 for order 1 and 1e-5 for order 2, absolute, |y| ≲ 3.
    info = lib.info
    outs = [n for n, c in info.causality.items() if c == "output"]
    vrs = [info.vr[n] for n in outs]
    delta, t0 = 1e-3, SETTLE
    y0 = np.array(driven.get_float64(vrs)[1])
    assert driven.do_step(t0, delta)[0] == OK
    y1 = np.array(driven.get_float64(vrs)[1])
    d1 = np.array(driven.get_output_derivatives(vrs, [1] * len(vrs))[1])
    d2 = np.array(driven.get_output_derivatives(vrs, [2] * len(vrs))[1])
    assert driven.do_step(t0 + delta, delta)[0] == OK
    y2 = np.array(driven.get_float64(vrs)[1])
    assert np.max(np.abs(y2 - y0)) < 0.1  # no angle wraps between the samples
    fd1, fd2 = (y2 - y0) / (2 * delta), (y2 - 2 * y1 + y0) / delta**2
    bad1 = {n: (a, b) for n, a, b in zip(outs, d1, fd1) if abs(a - b) > 1e-6}
    bad2 = {n: (a, b) for n, a, b in zip(outs, d2, fd2) if abs(a - b) > 1e-5}
    assert not bad1, bad1
    assert not bad2, bad2


@pytest.mark.parametrize(
    "vr_name, order, message",
    [
        ("tau_body[1]", 1, "value reference 8 is not an output (a state or a calculated output)"),
        ("tolerance", 1, "is not an output"),
        ("time", 1, "value reference 0 is not an output"),
        ("w_body[1]", 0, "derivative order 0 of 'w_body[1]' is not 1..2 (maxOutputDerivativeOrder)"),
        ("w_body[1]", 3, "derivative order 3 of 'w_body[1]' is not 1..2 (maxOutputDerivativeOrder)"),
    ],
)
def test_fmi3_output_derivatives_refuse_what_is_not_an_output_or_order(lib, driven, vr_name, order, message):
    status, _ = driven.get_output_derivatives([lib.info.vr["w_body[2]"], lib.info.vr[vr_name]], [1, order])
    assert status == ERROR
    assert any(message in m and "fmi3GetOutputDerivatives" in m for m in driven.errors_since(0)), driven.log


def test_fmi3_output_derivatives_refuse_a_wrong_count_a_state_and_model_exchange(lib, driven):
    vr = lib.info.vr["w_body[1]"]
    assert driven.get_output_derivatives([vr], [1], n_values=2)[0] == ERROR
    assert any("nValues (2) must equal nValueReferences (1)" in m for m in driven.errors_since(0))
    fresh = lib.instantiate()  # Instantiated: no outputs yet
    assert fresh.get_output_derivatives([vr], [1])[0] == ERROR
    assert any("fmi3GetOutputDerivatives: not allowed in state Instantiated" in m for m in fresh.errors_since(0))
    fresh.free()
    me = lib.instantiate(model_exchange=True)
    assert me.enter_initialization_mode(0.0) == OK
    assert me.get_output_derivatives([vr], [1])[0] == ERROR
    assert any("output derivatives are a Co-Simulation call" in m for m in me.errors_since(0)), me.log
    me.free()


# ---- FMI 2.0 through fmpy: the same core, and the inputs' derivatives in order 2 ----


def test_fmi2_output_derivatives_with_and_without_input_derivatives(torque_driven_fmi2):
    from fmpy.fmi1 import FMICallException

    s = Slave2(torque_driven_fmi2, {"method": METHODS["rk8"].value, "tolerance": 1e-12})
    try:
        taus = _names("tau_body", 3) + _names("tau_world", 3)
        s.s.setReal(s.names(taus), [*TAU_B, *TAU_W])
        s.s.doStep(0.0, SETTLE)
        q, w = s.get(_names("q", 4)), s.get(_names("w_body", 3))
        wv = s.names(_names("w_body", 3))
        # held inputs (the doStep cleared nothing was set): τ̇ = 0 in order 2
        want = closed_forms(q, w)
        assert np.array(s.s.getRealOutputDerivatives(wv, [1] * 3)) == pytest.approx(want["w_body"], rel=0, abs=1e-14)
        assert np.array(s.s.getRealOutputDerivatives(wv, [2] * 3)) == pytest.approx(want["w_body2"], rel=0, abs=1e-14)
        # input derivatives set for the next doStep enter order 2 (ω̈ gains I⁻¹ τ̇_b), not order 1
        tau_dot = np.array([0.5, -1.0, 2.0])
        s.s.setRealInputDerivatives(s.names(_names("tau_body", 3)), [1] * 3, list(tau_dot))
        want = closed_forms(q, w, tau_dot)
        assert np.array(s.s.getRealOutputDerivatives(wv, [1] * 3)) == pytest.approx(want["w_body"], rel=0, abs=1e-14)
        assert np.array(s.s.getRealOutputDerivatives(wv, [2] * 3)) == pytest.approx(want["w_body2"], rel=0, abs=1e-14)
        Slave2.messages.clear()
        with pytest.raises(FMICallException):
            s.s.getRealOutputDerivatives([s.vr["tau_body[1]"]], [1])
        with pytest.raises(FMICallException):
            s.s.getRealOutputDerivatives(wv[:1], [3])
        assert any("fmi2GetRealOutputDerivatives: value reference 8 is not an output" in m for m in Slave2.messages)
        assert any("derivative order 3 of 'w_body[1]' is not 1..2" in m for m in Slave2.messages), Slave2.messages
    finally:
        s.close()
