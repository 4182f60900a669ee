"""The work limit of one doStep: a tunable parameter, counted in right-hand-side evaluations, refusing before the work.

Work is internal steps times the method's cost (modelsrc/methods.py), every attempt of a
doStep included (docs/fmi_layer.md, Work limit). The work a doStep was charged is read
with the test accessor tests/c/introspect.c, so these tests check the accounting exactly
and that a refused doStep did no work, without timing anything (the wall time at the
limit is measured by `rbfmu bench`, docs/robustness.md §1).
"""

from __future__ import annotations

import math
import time

import pytest

from modelsrc.methods import METHODS, WORK_LIMIT, WORK_LIMIT_MAX

from ..harness.fmi3_ctypes import OK, shared_library
from ..harness.misuse_helpers import refused, stepping

STATES = ("q[1]", "q[2]", "q[3]", "q[4]", "w_body[1]", "w_body[2]", "w_body[3]")


def _stepping(free, method: str, **values: float):
    """An extreme_free instance in step mode with `method` and the start values given."""
    assert free.method_value[method] == METHODS[method].value  # the FMU's enumeration is the table's
    return stepping(free.fmi, method, **values)


def _refused_step(free, inst, *fragments: str) -> float:
    """One doStep of 1e-2 s from t = 0 that must be refused with every fragment in its
    message, leaving the time and the state as they were; returns its wall time (s)."""
    vr = free.fmi.info.vr
    before = inst.get_float64([vr[n] for n in ("time", *STATES)])
    n = len(inst.log)
    tic = time.perf_counter()
    status = inst.do_step(0.0, 1e-2)[0]
    wall = time.perf_counter() - tic
    refused(inst, status, n, *fragments)
    assert inst.get_float64([vr[n] for n in ("time", *STATES)]) == before
    return wall


def _set(inst, **values: float) -> int:
    vr = inst.lib.info.vr
    return inst.set_float64([vr[n] for n in values], list(values.values()))


def test_work_limit_is_a_tunable_parameter_checked_like_h_max(free):
    info = free.fmi.info
    assert "work_limit" in info.vr, "the FMU has no work_limit parameter"
    assert (info.causality["work_limit"], info.variability["work_limit"]) == ("parameter", "tunable")
    assert info.start["work_limit"] == WORK_LIMIT == 5e7
    inst = _stepping(free, "rk4")
    vr = info.vr["work_limit"]
    assert _set(inst, work_limit=5e7) == OK and inst.get_float64([vr]) == (OK, [5e7])  # tunable in step mode
    for bad, fragment in ((0.0, "work_limit must be > 0"), (-1.0, "work_limit must be > 0"), (math.nan, "finite")):
        n = len(inst.log)
        refused(inst, _set(inst, work_limit=bad), n, "fmi3SetFloat64", fragment)
        assert inst.get_float64([vr]) == (OK, [5e7])  # the old value kept
    inst.free()


def test_gauss6_at_h_max_1e_10_is_refused_before_any_work(free):
    """The case that ran for about 11 minutes: 1e8 Gauss-6 steps for one doStep of 1e-2 s.
    Refused at once, naming the work, the limit, its value and how to raise it; the state
    and the time are unchanged, and a sane h_max steps on."""
    assert "work_limit" in free.fmi.info.vr, "no work limit: this doStep would run for minutes"
    inst = _stepping(free, "gauss6", h_max=1e-10)
    wall = _refused_step(
        free,
        inst,
        "fmi3DoStep: the step 0.01 from t=0 (h_max 1e-10",
        "needs 1e+08 internal steps of method gauss6 at 2200 right-hand-side evaluations each: 2.2e+11 evaluations",
        "more than work_limit = 5e+07; raise the tunable parameter work_limit",
    )
    assert free.acc.rbtest_last_work(inst.handle) == 0.0  # refused before any internal step
    assert _set(inst, h_max=1e-3) == OK and inst.do_step(0.0, 1e-2)[0] == OK
    print(f"\ngauss6 at h_max 1e-10: refused in {wall * 1e3:.3f} ms")
    inst.free()


@pytest.mark.parametrize("method", list(METHODS))
def test_work_is_steps_times_cost_and_the_limit_is_inclusive(free, method):
    """100 internal steps (H = 1e-2 at h_max 1e-4; the spin of 1 rad/s needs fewer) cost
    100 x the method's cost: a limit of exactly that runs, one just below is refused."""
    cost = METHODS[method].cost
    inst = _stepping(free, method, h_max=1e-4, work_limit=100 * cost)
    assert inst.do_step(0.0, 1e-2)[0] == OK, inst.log
    assert free.acc.rbtest_last_substeps(inst.handle) == 100
    assert free.acc.rbtest_last_work(inst.handle) == 100 * cost
    assert _set(inst, work_limit=100 * cost * (1 - 1e-12)) == OK
    n = len(inst.log)
    refused(inst, inst.do_step(1e-2, 1e-2)[0], n, f"needs 100 internal steps of method {method}", "work_limit")
    assert free.acc.rbtest_last_work(inst.handle) == 0.0
    inst.free()


def test_refinements_count_against_the_limit(free):
    """A torque of 1e5 N m spins the body from 1 to ~1e3 rad/s within the step: rk4's first
    attempt (10 substeps at h_max 1e-3) ends with the rotation limit asking for ~50, so
    the step is redone with those: 4 x (10 + n) evaluations in all. With work_limit 200
    the refinement is refused before it runs, and the message says why it was needed."""
    inst = _stepping(free, "rk4", **{"tau_body[1]": 1e5})
    assert inst.do_step(0.0, 1e-2)[0] == OK, inst.log
    n2 = free.acc.rbtest_last_substeps(inst.handle)
    assert 40 < n2 < 70  # h |w| <= 0.2 at |w| ~ 1e3 rad/s
    assert free.acc.rbtest_last_work(inst.handle) == 4 * (10 + n2)
    inst.free()
    inst = _stepping(free, "rk4", work_limit=200.0, **{"tau_body[1]": 1e5})
    n = len(inst.log)
    refused(
        inst,
        inst.do_step(0.0, 1e-2)[0],
        n,
        "refining the step 0.01 from t=0, in which the spin rate kept growing with 10 substeps",
        f"needs {n2} internal steps of method rk4",
        f"{40 + 4 * n2} evaluations with those this doStep already spent, more than work_limit = 200",
    )
    assert free.acc.rbtest_last_work(inst.handle) == 40  # the first attempt, not the refused one
    assert inst.get_float64([free.fmi.info.vr["time"]]) == (OK, [0.0])
    inst.free()


def test_an_overflowing_step_stops_each_attempt_early(free):
    """tau = 1e200 N m at h_max 1e-8 (1e6 substeps): the state overflows in the second
    substep; each attempt stops at the next check (every 64 substeps) instead of running
    its 1e6 x 2^k substeps, and the refinements stop when the next would exceed the limit:
    attempts of 1e6, 2e6, 4e6 and 8e6 substeps cost 4 x 64 x 4 evaluations; the 1.6e7 of
    the fifth (6.4e7) would exceed 5e7."""
    inst = _stepping(free, "rk4", h_max=1e-8, **{"tau_body[1]": 1e200})
    wall = _refused_step(
        free,
        inst,
        "in which the state became non-finite with 8000000 substeps",
        "needs 1.6e+07 internal steps of method rk4",
        "more than work_limit = 5e+07",
    )
    assert free.acc.rbtest_last_work(inst.handle) == 4 * 64 * 4
    print(f"\noverflowing rk4 step at h_max 1e-8: refused after {wall * 1e3:.2f} ms")
    inst.free()


# ---- work_limit has a documented maximum, below 2^53 ----------------------------------------


def test_work_limit_above_its_maximum_is_refused_with_the_range():
    """9e20 made rb_budget_steps_left loop forever (k - 1 == k beyond 2^53); the maximum
    1e15 keeps every step count exact, and a value above it is refused in step mode and at
    exitInitializationMode, naming the value and the allowed range."""
    assert WORK_LIMIT_MAX < 2.0**53
    lib = shared_library("extreme_free")
    vr = lib.info.vr["work_limit"]
    inst = stepping(lib, "gauss4", tolerance=1e-10)
    for bad in (9e20, 1.3e21, 2.0**53):
        n = len(inst.log)
        text = refused(inst, inst.set_float64([vr], [bad]), n, "fmi3SetFloat64", "work_limit must be <= 1e+15")
        assert f"work_limit={bad:.17g}" in text and "0 < work_limit <= 1e+15" in text
        assert inst.get_float64([vr]) == (OK, [5e7])
    # the maximum itself is accepted, and a doStep under it returns
    assert inst.set_float64([vr], [WORK_LIMIT_MAX]) == OK
    assert inst.do_step(0.0, 1e-2)[0] == OK, inst.errors_since(0)
    inst.free()
    inst = lib.instantiate()
    assert inst.set_float64([vr], [9e20]) == OK  # checked with the others at exitInitializationMode
    assert inst.enter_initialization_mode(0.0) == OK
    n = len(inst.log)
    refused(inst, inst.exit_initialization_mode(), n, "fmi3ExitInitializationMode", "work_limit must be <= 1e+15")
    inst.free()
