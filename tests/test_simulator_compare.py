"""The report's rotor-scene comparison with a spacecraft simulator's 15 µs RK4 step (issue 28).

At equal error a fixed-step RK4 of the same equations needs the steps the FMU's rk4 line
needed; on a line of exact order 4 the log–log interpolation between two rungs gives the
steps of the power law exactly, so the expected figures follow from e ∝ N⁻⁴ alone.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rbcheck.workprecision.batch import SceneResult
from rbcheck.workprecision.measures import Best, LevelRow, Line, Point
from rbcheck.workprecision.references import Reference
from rbcheck.workprecision.simulator_compare import SIMULATOR_STEP_S, simulator_markdown, simulator_rows


def _point(work: int, err: float, wall: float) -> Point:
    return Point("h", 0.0, wall, err, err, err, work=work)


def _result(fmu: Best, level: float = 1e-7, resolved: bool = True, n_comm: int = 10) -> SceneResult:
    rk4 = Line("FMU rk4", "FMU", [_point(100, 1e-6, 1e-3), _point(200, 1e-6 / 16, 2e-3)])
    row = LevelRow(level, fmu.line, fmu.time, fmu, Best(None, None), Best(None, None), None, None, resolved)
    ref = Reference(np.zeros(1), np.zeros((1, 3)), np.zeros((1, 4)), "test", 1e-14, 1.0, 0.0)
    return SceneResult("dual_spin", 1.0, 0.1, n_comm, ref, [rk4], [row])


def test_steps_at_equal_error_follow_rk4s_order_and_the_ratio_is_the_simulators_time_over_the_fmus():
    rows = simulator_rows(_result(Best("FMU rk8", 1e-4)))
    assert len(rows) == 1
    r = rows[0]
    steps = 100 * (1e-6 / 1e-7) ** 0.25  # e ∝ N^-4 through the rung (100 steps, 1e-6)
    assert r.steps == pytest.approx(steps, rel=1e-12)
    assert r.simulator_s == pytest.approx(steps * SIMULATOR_STEP_S, rel=1e-12)
    assert r.ratio == pytest.approx(steps * SIMULATOR_STEP_S / 1e-4, rel=1e-12)
    assert not r.at_most and not r.fmu_upper
    text = "\n".join(simulator_markdown(_result(Best("FMU rk8", 1e-4)), 3))
    assert f"| {math.floor(r.ratio + 0.5):.0f}× |" in text and "this scene has 3" in text


def test_bounds_are_marked_and_unresolved_or_unreached_levels_are_left_out():
    # the rk4 line's coarsest rung (100 steps) already meets 1e-5: at most 100 steps, so at most the ratio ...
    (r,) = simulator_rows(_result(Best("FMU rk8", 1e-4), level=1e-5, n_comm=10))
    assert r.at_most and r.steps == 100
    assert "≤" in simulator_markdown(_result(Best("FMU rk8", 1e-4), level=1e-5, n_comm=10), 1)[-2]
    # ... unless those were one step per communication step: no simulator writing the same points takes fewer
    (r,) = simulator_rows(_result(Best("FMU rk8", 1e-4), level=1e-5, n_comm=100))
    assert not r.at_most and r.steps == 100
    (r,) = simulator_rows(_result(Best("FMU rk8", 1e-4), level=1e-7, n_comm=1000))  # 178 steps needed, 1000 taken
    assert not r.at_most and r.steps == 1000
    # the FMU's time only an upper bound: the ratio is a lower bound
    (r,) = simulator_rows(_result(Best("FMU rk8", 1e-4, upper_bound=True)))
    assert r.fmu_upper and "≥" in simulator_markdown(_result(Best("FMU rk8", 1e-4, upper_bound=True)), 1)[-2]
    assert simulator_rows(_result(Best("FMU rk8", 1e-4), resolved=False)) == []
    assert simulator_rows(_result(Best("FMU rk8", 1e-4), level=1e-9)) == []  # rk4 never got there
    assert simulator_rows(_result(Best(None, None))) == []
    assert simulator_markdown(_result(Best(None, None)), 1) == []
