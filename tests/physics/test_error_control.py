"""Error-controlled internal steps: achieved error against the tolerance, h_max as a cap, landing, rejections, budget.

docs/theory.md §5.5. The tolerance is a relative error per second: every accepted step of h
seconds has an estimated error of at most tolerance·h, so after T seconds the error is about
tolerance·T, times what the flow does to the local errors (it amplifies them on the
tennis-racket flips, e^(λT) with λ = 0.58 1/s on free_asymmetric) and times how far each
method's estimate over-states its error (rk4's and the Gauss methods' estimates are of a
lower-order companion, pessimistic by a factor 1/h and more). Every measured number is
printed (pytest -s) and quoted in docs/theory.md §5.5.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from modelsrc.methods import DEFAULT_TOLERANCE, METHODS, error_controlled
from modelsrc.scene import load_scene
from rbcheck.workprecision.references import closed_form

from ..harness.control_harness import AskingInstance, library, relative_error, simulate
from ..harness.fmi3_ctypes import OK, shared_library
from ..harness.misuse_helpers import stepping

EPS = float(np.finfo(float).eps)
CONTROLLED = tuple(m for m in METHODS if error_controlled(m))  # rk4, rk8 and the Gauss methods
TOLERANCES = tuple(10.0**-k for k in range(3, 13))
# (scene, stop time T, communication step H): free_asymmetric over 4 s (before its first
# flip: the flow amplifies local errors by at most e^(0.58·4) = 10 there) with steps long
# enough (0.5 s) that the error control, not the communication step, sets the internal
# steps; heavy_top over 0.2 s (1.2 nutation periods of 0.17 s, 30 rad of spin at 150 rad/s).
CASES = (("free_asymmetric", 4.0, 0.5), ("heavy_top", 0.2, 0.05))
# The implicit midpoint rule (order 2) needs h ~ sqrt(tolerance): on heavy_top below 1e-8
# one doStep of 0.05 s needs > 1e5 steps of 200 right-hand-side evaluations, more than the
# default work_limit (5e7) admits (that refusal is tested below); on free_asymmetric 1e-12
# takes 0.1 s.
SMALLEST = {("heavy_top", "implicit_midpoint"): 1e-8}
# The band of error / (tolerance·T) (docs/theory.md §5.5): measured 2e-10 .. 1.9 over all
# cases (the largest: implicit midpoint, whose estimate is its exact leading error term,
# times the amplification of the flow). 3 leaves room for the amplification only.
BAND_HIGH = 3.0
# Round-off floor: every internal step rounds each state component by a few ε, and those
# roundings add up at worst linearly: 4 N ε after N steps. Where tolerance·T falls below
# it (rk4 at 1e-11, 1e-12 takes 1e4-1e5 steps) the error stops following the
# tolerance. An implicit step also leaves its Newton residual (stopped at 1e-14 absolute on
# the stage increments, integrators.gauss_step), mostly far below ε.
ROUNDOFF_PER_STEP = 4 * EPS
# Monotone within a factor: a tenfold smaller tolerance never gives a larger error by more
# than 3x (measured: at most 1.8x, rk4 at 1e-12 where the estimate floor 1e-16 sets the
# step instead of tolerance·h, docs/theory.md §5.5), unless both are at the round-off floor.
MONOTONE_FACTOR = 3.0


def _fmu(fmus, name):
    return library(fmus[name])


@pytest.mark.slow
@pytest.mark.parametrize("name,T,H", CASES)
def test_error_follows_the_tolerance(fmus, name, T, H):
    scene = load_scene(name)
    w_ref, q_ref, source = closed_form(scene, np.array([0.0, T]))
    lib = _fmu(fmus, name)
    n = round(T / H)
    print(f"\n{name}: T = {T} s, H = {H} s, reference {source}")
    print(f"{'method':18s} {'tolerance':>9s} {'error':>9s} {'err/(tol T)':>11s} {'steps':>7s} {'rejected':>8s}")
    for method in CONTROLLED:
        assert error_controlled(method)
        previous = None
        for tol in TOLERANCES:
            if tol < SMALLEST.get((name, method), 0.0):
                continue
            run = simulate(lib, [H] * n, {"tolerance": tol}, method)
            assert run.status == OK, run.log
            err = relative_error(run, w_ref[-1], q_ref[-1])
            steps = float(run.report["internal_steps"].sum())
            floor = ROUNDOFF_PER_STEP * steps
            print(
                f"{method:18s} {tol:9.0e} {err:9.2e} {err / (tol * T):11.3g} {steps:7.0f} "
                f"{run.report['rejected_steps'].sum():8.0f}"
            )
            assert err <= BAND_HIGH * tol * T + floor, (method, tol, err)
            if previous is not None:
                assert err <= MONOTONE_FACTOR * previous + floor, (method, tol, err, previous)
            previous = err


def _start(extra: dict[str, float] | None = None) -> dict[str, float]:
    """extreme_free (I = diag(1, 2, 3)) tumbling: spin about all three axes."""
    return {"w_body[1]": 0.3, "w_body[2]": 1.0, "w_body[3]": 0.2, "h_max": 0.0, **(extra or {})}


def test_h_max_caps_the_error_controlled_steps():
    lib = shared_library("extreme_free")
    H, h_max = 0.1, 0.013
    steps = [H] * 20
    run = simulate(lib, steps, _start({"tolerance": 1e-6, "h_max": h_max}), "rk8")
    assert run.status == OK, run.log
    # rk8 at 1e-6 and |ω| = 1 rad/s would take steps of ~0.1 s and more: the cap binds
    assert np.all(run.report["h_last"] <= h_max)
    assert np.all(run.report["h_next"] <= h_max)
    assert np.all(run.report["internal_steps"] >= math.ceil(H / h_max))
    # the FMU's time after each doStep is the importer's t + H: no drift of the clock
    assert np.array_equal(run.time, np.concatenate([[0.0], np.cumsum(steps)]))
    # uncapped, the same doSteps take one step each
    free = simulate(lib, steps, _start({"tolerance": 1e-6}), "rk8")
    assert free.report["internal_steps"].max() < math.ceil(H / h_max)


def _accepted_ends(asked: list[float], t0: float) -> tuple[list[float], int]:
    """The end times of the accepted rk4 steps of a doStep from t0, and the number of
    attempts, from the times the FMU asked for inputs: nodes 1/2 and 1 of each attempt
    (integrators.stage_nodes("rk4")). An attempt is accepted when the next one starts where
    it ended, rejected when the next one starts where it started (start = 2 t_half − t_end,
    to a few ulps: compared with a margin of 1e-9 of the step)."""
    pairs = list(zip(asked[0::2], asked[1::2]))
    ends, start = [], t0
    for (mid, end), nxt in zip(pairs, pairs[1:] + [None]):
        assert abs((2 * mid - end) - start) <= 1e-9 * (end - mid), (start, mid, end)
        if nxt is None or abs((2 * nxt[0] - nxt[1]) - end) <= 1e-9 * (end - mid):
            ends.append(end)
            start = end
    return ends, len(pairs)


def test_a_rejected_step_is_redone_from_its_start_state():
    """A doStep at tolerance 1e-12 right after one at 1e-3: its first attempt, at the long
    step h_next that 1e-3 allowed, is rejected. The accepted steps, read from the times the
    FMU asks for inputs (FMI 3.0 intermediate update), are replayed as doSteps of one fixed
    step each: the same steps from the same start states give the same state to round-off.
    A rejected attempt that leaked into the state (its increment, its FSAL derivative, its
    compensation) would differ by the rejected step's error, ~1e-5 here."""
    lib = shared_library("extreme_free")
    info = lib.info
    names = [f"w_body[{k}]" for k in (1, 2, 3)] + [f"q[{k}]" for k in (1, 2, 3, 4)]
    H = 0.5
    inst = AskingInstance(lib, ["tau_body[1]", "tau_body[2]", "tau_body[3]"])
    try:
        start = _start({"tolerance": 1e-3})
        assert inst.set_float64([info.vr[k] for k in start], list(start.values())) == OK
        assert inst.set_int64([info.int64_vrs["method"]], [1]) == OK  # rk4
        assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK
        assert inst.do_step(0.0, H)[0] == OK
        assert inst.set_float64([info.vr["tolerance"]], [1e-12]) == OK
        inst.asked.clear()
        assert inst.do_step(H, H)[0] == OK, inst.log
        rejected = inst.get_float64([info.vr["rejected_steps"]])[1][0]
        accepted = inst.get_float64([info.vr["internal_steps"]])[1][0]
        x_controlled = np.array(inst.get_float64([info.vr[k] for k in names])[1])
    finally:
        inst.free()
    ends, attempts = _accepted_ends(inst.asked, H)
    assert rejected > 0
    assert len(ends) == accepted and attempts == accepted + rejected
    # the last step lands exactly on the communication point t + H
    assert ends[-1] == 2 * H
    # replay: the same first doStep, then one doStep per accepted step with fixed steps
    # (tolerance 0, h_max 0: one internal step each, inside rk4's limits at |ω| ~ 1 rad/s)
    begins = [H, *ends[:-1]]
    replay = [H] + [end - begin for begin, end in zip(begins, ends)]
    fixed = simulate(
        lib, replay, _start({"tolerance": 1e-3}), "rk4", names=names, times=[0.0, *begins],
        retune={1: {"tolerance": 0.0}},
    )  # fmt: skip
    assert fixed.status == OK and np.all(fixed.report["internal_steps"][1:] == 1), fixed.log
    x_fixed = np.array([fixed.out[k][-1] for k in names])
    # round-off: the two runs differ only in how each step's start is rounded (time, the
    # compensated sum restarted at every doStep): a few ε per step on states of size 1
    n = len(ends)
    assert np.max(np.abs(x_fixed - x_controlled)) <= 8 * n * EPS, np.max(np.abs(x_fixed - x_controlled))
    print(f"\nrejected {rejected:.0f}, accepted {accepted:.0f}: |replay - controlled| = "
          f"{np.max(np.abs(x_fixed - x_controlled)):.1e}")  # fmt: skip


def test_the_work_budget_refuses_an_error_controlled_step_quickly():
    """rk4 at tolerance 1e-12 over a 100 s doStep needs ~3e4 steps (h ~ 3e-3 s at 1 rad/s);
    work_limit = 4000 evaluations admits 1000: refused, with a message naming the limit."""
    import time

    lib = shared_library("extreme_free")
    tic = time.process_time()
    run = simulate(lib, [100.0], _start({"tolerance": 1e-12, "work_limit": 4000.0}), "rk4")
    wall = time.process_time() - tic
    assert run.status != OK
    message = " ".join(run.log)
    assert "work_limit = 4000" in message and "error-controlled" in message, message
    # the refusal comes at the step that would exceed the limit: 1000 rk4 steps of a free
    # body cost ~0.1 ms in C; the whole instantiate-run-free takes milliseconds of CPU time
    # (CPU time, not wall time: other test workers delay it without making it cost more)
    assert wall < 1.0
    # the state is left at the start of the refused doStep
    assert run.time[-1] == 0.0


def test_tolerance_zero_takes_fixed_steps_and_reports_them():
    lib = shared_library("extreme_free")
    H, h_max = 0.01, 0.003
    run = simulate(lib, [H] * 50, _start({"tolerance": 0.0, "h_max": h_max}), "rk8")
    assert run.status == OK, run.log
    n = math.ceil(H / h_max)  # 4: rk8's limits (1.5/||J||, 0.5 rad / |ω|) allow far longer steps
    assert np.all(run.report["internal_steps"] == n)
    assert np.all(run.report["rejected_steps"] == 0)
    assert np.all(run.report["h_last"] == H / n)
    assert np.all(run.report["h_next"] == 0.0)  # no proposal: fixed stepping proposes none


@pytest.mark.parametrize("method", [m for m in ("splitting", "exact_free") if m in METHODS])
def test_methods_without_estimate_take_fixed_steps_at_any_tolerance(method):
    """The splittings have no embedded estimate (docs/theory.md §5.5): with the default
    tolerance they take the same fixed steps as with tolerance 0."""
    assert not error_controlled(method)
    lib = shared_library("extreme_free")
    H, h_max = 0.01, 0.003
    runs = [simulate(lib, [H] * 20, _start({"tolerance": tol, "h_max": h_max}), method) for tol in (1e-10, 0.0)]
    for run in runs:
        assert run.status == OK, run.log
        assert np.all(run.report["internal_steps"] == math.ceil(H / h_max))
        assert np.all(run.report["rejected_steps"] == 0)
    assert np.array_equal(runs[0].w, runs[1].w) and np.array_equal(runs[0].q, runs[1].q)


@pytest.mark.parametrize("method", ["gauss4", "gauss6"])
def test_gauss_steps_under_error_control_keep_the_quadratic_invariants(method):
    """The Gauss steps' estimate is an explicit companion step (docs/theory.md §5.5), but
    the state goes on with the Gauss step: under error control, at steps that change from
    one to the next, |L| and E of the free body stay exact up to the Newton tolerance and
    round-off, as at fixed steps (tests/physics/test_methods.py), where the companion would drift."""
    lib = shared_library("extreme_free")
    run = simulate(lib, [0.5] * 40, _start({"tolerance": 1e-8}), method)  # 20 s, tumbling
    assert run.status == OK, run.log
    I = np.array([1.0, 2.0, 3.0])  # extreme_free's principal moments, kg m² (body frame)
    L = np.linalg.norm(I * run.w, axis=1)
    E = 0.5 * np.sum(I * run.w**2, axis=1)
    steps = run.report["internal_steps"]
    print(
        f"\n{method}: {steps.sum():.0f} steps, {steps.min():.0f}..{steps.max():.0f} per doStep, "
        f"{run.report['rejected_steps'].sum():.0f} rejected; |L| drift "
        f"{np.ptp(L) / L[0]:.1e}, E drift {np.ptp(E) / E[0]:.1e}"
    )
    assert steps.min() < steps.max()  # the controller changed the step
    # Newton stops at 1e-14 absolute on the stage increments; a few hundred steps: 1e-13
    assert np.ptp(L) / L[0] < 1e-13 and np.ptp(E) / E[0] < 1e-13


def test_default_tolerance_is_error_control():
    """The shipped scenes step by error control: tolerance 1e-10 per second, h_max 0 (no cap)."""
    assert DEFAULT_TOLERANCE == 1e-10
    scene = load_scene("heavy_top")
    assert scene.tolerance == DEFAULT_TOLERANCE and scene.h_max == 0.0 and scene.method == "rk8"


@pytest.mark.parametrize("method", CONTROLLED)
def test_a_state_that_overflows_is_refused_never_nan(method):
    """A spin of 1e154 rad/s (its energy 5e307 still finite: 1e160 is refused at
    initialisation since the outputs must stay finite, issue 23.11): the quaternion's
    stages q ω overflow within a step. Every attempt's estimate is then NaN or infinite and
    is rejected (the loop checks no state per step, rbfmu_control.c), so the doStep must end
    refused with a message, the state left finite at its start, not accepted as NaN."""
    lib = shared_library("extreme_free")
    run = simulate(lib, [0.01], _start({"tolerance": 1e-6, "w_body[1]": 1e154}), method)
    assert run.status != OK
    message = " ".join(run.log)
    print(f"\n{method}: {message[:300]}")
    assert "step" in message, message
    assert run.time[-1] == 0.0
    assert np.all(np.isfinite(run.w)) and np.all(np.isfinite(run.q))
    assert run.w[-1][0] == 1e154


def test_a_burst_of_thrust_from_rest_is_stepped_under_error_control():
    """8e9 N on spacecraft_thruster from rest: the default (rk8, tolerance 1e-10) refused the
    doStep (its first internal step of 0.01 s overflowed in its stages); it now starts from
    the step the rates allow and agrees with fixed rk8 at 1e-6 s steps. Reference error: the
    fixed steps' error (rk8, h |w| <= 0.16 rad per step at the end) is far below the
    control's tolerance 1e-10/s; the agreement asked, 1e-9 relative to |w| = 1.6e5, is
    tolerance x T = 1e-12 times the growth of the error over 0.01 s (|dw/dw0| ~ h |w| ~ 1e3)."""
    lib = shared_library("spacecraft_thruster")
    vr = lib.info.vr
    results = {}
    for label, values in (
        ("controlled", {"tolerance": 1e-10, "h_max": 0.0}),
        ("fixed", {"tolerance": 0.0, "h_max": 1e-6}),
    ):
        inst = stepping(lib, "rk8", **values)
        assert inst.set_float64([vr["f_thruster[1]"]], [8e9]) == OK
        status = inst.do_step(0.0, 0.01)[0]
        assert status == OK, (label, inst.errors_since(0))
        results[label] = inst.get_float64([vr[f"w_body[{k}]"] for k in (1, 2, 3)])[1]
        inst.free()
    w_ref = results["fixed"]
    scale = math.sqrt(sum(v * v for v in w_ref))
    assert scale > 1e5  # the spin the burst reaches: |w| = 1.6e5 rad/s
    err = max(abs(a - b) for a, b in zip(results["controlled"], w_ref)) / scale
    print(f"\nthrust 8e9 N, 0.01 s: |w| = {scale:.6g} rad/s, error control vs fixed rk8: {err:.2e} relative")
    assert err < 1e-9
