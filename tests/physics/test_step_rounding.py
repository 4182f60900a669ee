"""Sub-step counts that do not depend on how the importer rounds its communication steps (docs/theory.md §5.4).

An importer that keeps its clock as t_k = t_0 + k·Δ hands the FMU H_k = t_(k+1) − t_k, which
differs from Δ by up to an ulp of t: at t ~ 1e4 s that is 1.8e-12 s, 1.8e-10 relative to
Δ = 0.01 s. The old count ceil(H/h_max·(1 − 1e-12)) then gave 11 sub-steps instead of 10 for
about half the steps; rb_steps_in's guard is 2ε((|t| + |t + H|)/H + 2), the relative spacing
of the times involved, so every H_k takes the same 10.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from ..harness.control_harness import simulate
from ..harness.fmi3_ctypes import OK, shared_library

EPS = float(np.finfo(float).eps)
DELTA, H_MAX, N = 0.01, 0.001, 1000


def _old_count(H: float) -> int:
    """The sub-step count before docs/theory.md §5.4's guard: a fixed relative slack 1e-12."""
    return math.ceil(H / H_MAX * (1.0 - 1e-12))


@pytest.mark.parametrize("t0", [0.0, 1e4])
def test_importer_rounded_steps_take_the_same_sub_steps(t0):
    times = [t0 + k * DELTA for k in range(N + 1)]
    steps = [b - a for a, b in itertools.pairwise(times)]
    assert sum(H != DELTA for H in steps) > N // 2  # the importer's H really are rounded
    lib = shared_library("extreme_free")
    start = {"w_body[1]": 0.3, "w_body[2]": 1.0, "w_body[3]": 0.2, "tolerance": 0.0, "h_max": H_MAX}
    rounded = simulate(lib, steps, start, "rk4", times=times[:-1], start_time=t0)
    exact = simulate(lib, [DELTA] * N, start, "rk4", start_time=t0)
    assert rounded.status == OK and exact.status == OK, rounded.log + exact.log
    # every doStep takes exactly DELTA / H_MAX = 10 sub-steps, whatever the rounding of H
    assert np.all(rounded.report["internal_steps"] == 10)
    assert np.all(exact.report["internal_steps"] == 10)
    old = [_old_count(H) for H in steps]
    print(f"\nt0 = {t0:g} s: H != {DELTA} in {sum(H != DELTA for H in steps)} of {N} steps; the old 1e-12 guard "
          f"would take 11 sub-steps in {sum(n == 11 for n in old)} of them, rb_steps_in in none")  # fmt: skip
    if t0 > 0:
        # at t ~ 1e4 s the old relative slack 1e-12 is below the ulp of t (1.8e-12 s = 1.8e-10 of
        # H): about half the steps would have taken an extra sub-step
        assert sum(n == 11 for n in old) > N // 4
    # same sub-steps: the states differ only by the steps' rounding. The sum of the H_k is
    # t_N − t_0, which differs from N·DELTA by an ulp of t (|ω| ~ 1 rad/s turns that into an
    # angle); each of the 1e4 sub-steps adds a few ε on states of size 1.
    ulp_t = math.ulp(max(t0, 1.0) + N * DELTA)
    diff = np.max(np.abs(np.hstack([rounded.q[-1] - exact.q[-1], rounded.w[-1] - exact.w[-1]])))
    assert diff <= 4 * ulp_t + 4 * 10 * N * EPS, diff
    print(f"  |rounded - exact| = {diff:.1e}")
