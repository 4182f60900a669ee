"""Every path by which a state enters the FMU checks its values; no Get returns a non-finite value with OK.

The rule of docs/robustness.md (Values entering and leaving the FMU), issue 39 items 3, 4
and 11: start values at exitInitializationMode, Model Exchange SetContinuousStates, and
SetFMUState/DeserializeFMUState all pass the generated checks, and the state derivatives
and outputs at the state entering are finite; a refusal names the values. Uses the ctypes
harness (tests/harness/fmi3_ctypes.py) on the shipped dual_spin (a wheel) and
eccentric_orbit (the central field), each built once per process.
"""

from __future__ import annotations

import pytest

from ..harness.fmi3_ctypes import OK, Fmi3Instance, shared_library
from ..harness.fmu_state_bytes import StateBytes

ERROR, DISCARD = 3, 2


@pytest.fixture(scope="module")
def wheel():
    return shared_library("dual_spin")


@pytest.fixture(scope="module")
def orbit():
    return shared_library("eccentric_orbit")


def _started(lib, model_exchange: bool = False) -> Fmi3Instance:
    inst = lib.instantiate(model_exchange=model_exchange)
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK, inst.log
    return inst


def _log(inst: Fmi3Instance) -> str:
    return "\n".join(m for _, _, m in inst.log)


@pytest.mark.parametrize(
    ("scene", "state", "value"),
    [("eccentric_orbit", "x_cm[1]", 0.0), ("dual_spin", "Omega_wheel", 1e200)],
)
def test_a_start_value_outside_the_domain_is_refused_at_exit_initialization(scene, state, value):
    """Item 3 (start values) and item 11: exitInitializationMode refuses a start state at which
    the derivatives or outputs are not finite, naming the state's value; a Get of an output in
    the Error state that follows is refused too, never inf/NaN with OK."""
    lib = shared_library(scene)
    vr = lib.info.vr
    inst = lib.instantiate()
    names = [state] if scene == "dual_spin" else ["x_cm[1]", "x_cm[2]", "x_cm[3]"]
    assert inst.set_float64([vr[n] for n in names], [value] * len(names)) == OK
    assert inst.enter_initialization_mode(0.0) == OK
    assert inst.exit_initialization_mode() == ERROR
    assert f"{state}={value:.17g}" in _log(inst), _log(inst)
    outputs = [n for n in ("E_kin", "E_total") if n in vr]
    status, values = inst.get_float64([vr[n] for n in outputs])
    assert status != OK, (outputs, values)
    assert "would be" in _log(inst)


@pytest.mark.parametrize(
    ("scene", "state", "value"),
    [("eccentric_orbit", "x_cm", 0.0), ("dual_spin", "Omega_wheel", 1e200)],
)
def test_model_exchange_set_continuous_states_checks_the_state(scene, state, value):
    """Item 3 (Model Exchange): SetContinuousStates with x_cm = 0 or Omega_wheel = 1e200 is
    refused with Discard (FMI 3.0: a state outside the model's domain, try a smaller step),
    the log names the value, and the states stay as they were."""
    lib = shared_library(scene)
    inst = _started(lib, model_exchange=True)
    assert inst.enter_continuous_time_mode() == OK
    nx = len([n for n in lib.info.vr if n.startswith("der(")])
    status, x = inst.get_continuous_states(nx)
    assert status == OK
    vr = lib.info.vr
    states = sorted((n for n in vr if f"der({n})" in vr), key=lambda n: vr[n])
    bad = list(x)
    for k, n in enumerate(states):
        if n == state or n.startswith(state + "["):
            bad[k] = value
    assert bad != list(x), states
    assert inst.set_continuous_states(bad) in (DISCARD, ERROR)
    assert f"{states[[n.startswith(state) for n in states].index(True)]}={value:.17g}" in _log(inst), _log(inst)
    assert inst.get_continuous_states(nx) == (OK, x)
    status, dx = inst.get_derivatives(nx)
    assert status == OK and all(abs(d) < float("inf") for d in dx)


@pytest.mark.parametrize("name", ["Omega_wheel", "w_body[3]"])
def test_a_crafted_state_with_a_valid_crc_is_checked_like_a_start_value(wheel, name):
    """Item 4: a serialized state with a valid CRC carrying Omega_wheel or w_body[3] = 1e200
    is refused at DeserializeFMUState, naming the value; the instance steps on."""
    inst = _started(wheel)
    assert inst.do_step(0.0, 1e-2)[0] == OK
    status, snap = inst.get_fmu_state()
    assert status == OK
    status, size = inst.serialized_size(snap)
    status, data = inst.serialize(snap, size)
    assert status == OK
    crafted = StateBytes.parse(data).with_value(wheel.info.vr[name], 1e200).pack()
    status, _ = inst.deserialize(crafted)
    assert status == ERROR
    assert f"{name}={1e200:.17g}" in _log(inst), _log(inst)
    assert inst.do_step(1e-2, 1e-2)[0] == OK
    status, e = inst.get_float64([wheel.info.vr["E_kin"]])
    assert status == OK and abs(e[0]) < float("inf")
