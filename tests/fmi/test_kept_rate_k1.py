"""A second doStep, with the kept end rate and k1 or with new ones, ends bit for bit where a fresh one does.

The substep limits' rate and k1 = f(x) at a fixed-step doStep's start are the previous doStep's
end values while the states, inputs, parameters and method are bit for bit unchanged
(fmu/c/rbfmu_step.c, start_rate; docs/fmi_layer.md, Step cost). A doStep of an instance that
had one before must end where a fresh instance started at its state ends, with nothing set in
between (the kept values) and after a state, an input or a parameter was set (computed anew).
"""

from __future__ import annotations

import pytest

from ..harness.fmi3_ctypes import OK

STATES = [f"q[{k}]" for k in range(1, 5)] + [f"w_body[{k}]" for k in range(1, 4)]
INPUTS = [f"tau_body[{k}]" for k in range(1, 4)]
H = 1e-2


def _fresh(lib, t0: float, values: dict[str, float]):
    inst = lib.instantiate()
    vr = lib.info.vr
    assert inst.set_float64([vr[n] for n in values], list(values.values())) == OK, inst.log
    assert inst.enter_initialization_mode(t0) == OK and inst.exit_initialization_mode() == OK, inst.log
    return inst


def _get(lib, inst, names: list[str]) -> list[float]:
    status, v = inst.get_float64([lib.info.vr[n] for n in names])
    assert status == OK, inst.log
    return v


@pytest.mark.parametrize("change", [None, "state", ("tau_body[1]", 0.5), ("h_max", 2.5e-3)])
def test_second_dostep_equals_a_fresh_dostep_from_its_state(free_lib, change):
    """change: None (the kept values), "state" (the FMU state from before the first doStep
    restored: the states differ, states cannot be set in step mode), or (name, value) set: an
    input, or the tunable h_max (four substeps instead of one)."""
    start = {"w_body[1]": 0.3, "w_body[2]": 1.0, "w_body[3]": -2.0, "c_friction": 0.01, "h_max": 1e-2}
    start.update({"tau_body[1]": 0.0, "tau_body[2]": 0.1, "tau_body[3]": 0.0})
    a = _fresh(free_lib, 0.0, start)
    status, before = a.get_fmu_state()
    assert status == OK, a.log
    assert a.do_step(0.0, H)[0] == OK, a.log
    t, values = H, {**start, **dict(zip(STATES, _get(free_lib, a, STATES)))}
    if change == "state":
        assert a.set_fmu_state(before) == OK, a.log
        t, values = 0.0, {**start, **dict(zip(STATES, _get(free_lib, a, STATES)))}
    elif change is not None:
        name, v = change
        assert a.set_float64([free_lib.info.vr[name]], [v]) == OK, a.log
        values[name] = v
    assert a.do_step(t, H)[0] == OK, a.log
    b = _fresh(free_lib, t, values)
    names = STATES + INPUTS + ["c_friction", "h_max"]
    assert _get(free_lib, b, names) == [values[n] for n in names]  # taken as set, none rounded on entry
    assert b.do_step(t, H)[0] == OK, b.log
    assert _get(free_lib, a, STATES) == _get(free_lib, b, STATES)
