"""The report's three-wheel gyrostat against a spacecraft simulator's 15 µs RK4 step (issue 28).

At equal error a fixed-step RK4 of the same equations needs the steps the FMU's rk4 line
needed; on a line of exact order 4 the log–log interpolation between two rungs gives the
steps of the power law exactly, so the expected figures follow from e ∝ N⁻⁴ alone. The
FMU's compute is its cheapest method's steps at that error times its C cost per step.
"""

from __future__ import annotations

import numpy as np
import pytest

from rbcheck.workprecision.batch import SceneResult
from rbcheck.workprecision.measures import Best, LevelRow, Line, Point
from rbcheck.workprecision.references import Reference
from rbcheck.workprecision.simulator_compare import SIMULATOR_STEP_S, simulator_markdown, simulator_rows

NS = {"rk4": 50.0, "rk8": 200.0}  # C cost per internal step (ns)


def _point(work: int, err: float) -> Point:
    return Point("h", 0.0, 1e-3, err, err, err, work=work)


def _result(level: float = 1e-7, resolved: bool = True, n_comm: int = 10) -> SceneResult:
    rk4 = Line("FMU rk4", "FMU", [_point(100, 1e-6), _point(200, 1e-6 / 16)])  # order 4
    rk8 = Line("FMU rk8", "FMU", [_point(20, 1e-6), _point(40, 1e-6 / 256)])  # order 8
    fmu = Best("FMU rk8", 4e-3)
    row = LevelRow(level, fmu.line, fmu.time, fmu, Best(None, None), Best(None, None), None, None, resolved)
    ref = Reference(np.zeros(1), np.zeros((1, 3)), np.zeros((1, 4)), "test", 1e-14, 1.0, 0.0)
    return SceneResult("reaction_wheel_slew", 1.0, 0.1, n_comm, ref, [rk4, rk8], [row])


def test_equal_error_steps_follow_each_methods_order_and_the_ratio_compares_compute():
    (r,) = simulator_rows(_result(), NS)
    n4 = 100 * (1e-6 / 1e-7) ** 0.25  # e ∝ N^-4 through (100 steps, 1e-6)
    n8 = 20 * (1e-6 / 1e-7) ** 0.125  # e ∝ N^-8 through (20 steps, 1e-6)
    assert r.steps == pytest.approx(n4, rel=1e-12) and not r.at_most
    assert r.simulator_s == pytest.approx(n4 * SIMULATOR_STEP_S, rel=1e-12)
    # rk8: 21.8 steps x 200 ns = 4.4 us, cheaper than rk4's 177.8 x 50 ns = 8.9 us
    assert r.method == "rk8" and r.fmu_steps == pytest.approx(n8, rel=1e-12)
    assert r.fmu_s == pytest.approx(n8 * 200e-9, rel=1e-12)
    assert r.ratio == pytest.approx(n4 * SIMULATOR_STEP_S / (n8 * 200e-9), rel=1e-12)
    assert r.fmu_wall == 4e-3  # the measured wall time is shown, not used in the ratio
    # without rk8's C cost only rk4 can be priced
    (r4,) = simulator_rows(_result(), {"rk4": 50.0})
    assert r4.method == "rk4" and r4.ratio == pytest.approx(SIMULATOR_STEP_S / 50e-9, rel=1e-12)
    text = "\n".join(simulator_markdown(_result(), NS))
    assert f"| {r.ratio:.0f}× |" in text


def test_one_step_per_communication_point_is_the_floor_and_bounds_or_unresolved_levels_are_left_out():
    # rk4's coarsest rung (100 steps) meets 1e-5: with 10 communication steps fewer might do: no figure
    assert simulator_rows(_result(level=1e-5, n_comm=10), NS) == []
    # ... with 100 communication steps no simulator writing them takes fewer: exact
    (r,) = simulator_rows(_result(level=1e-5, n_comm=100), NS)
    assert r.steps == 100 and not r.at_most
    assert simulator_rows(_result(resolved=False), NS) == []
    assert simulator_rows(_result(level=1e-9), NS) == []  # rk4 never got there
    assert simulator_rows(_result(), {}) == [] and simulator_markdown(_result(), {}) == []
