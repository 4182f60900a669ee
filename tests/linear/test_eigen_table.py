"""The eigenvalue table: a marginal mode's columns are those of Re s = 0, and the columns never run together.

Before: `rbfmu linearize skewed_bar` printed s = −2.2e-135 with damping 1 and a time constant
of 4.5e134 s, and for 2.6e-113 ± 10j a damping and a time constant that ran into one field
("10-2.6e-114-3.848e+112"): round-off in Re s read as physics.
"""

from __future__ import annotations

import math

import numpy as np

from fmu.linear.eigen import modes, table
from fmu.linear.linear_model import LinearModel


def model(A: np.ndarray) -> LinearModel:
    n = A.shape[0]
    states = tuple(f"x{k}" for k in range(n))
    empty = (np.zeros((n, 0)), np.zeros((0, n)), np.zeros((0, 0)))
    return LinearModel(A, *empty, states, (), (), None)  # type: ignore[arg-type]  # no operating point needed


def test_a_marginal_pair_has_zero_damping_and_no_time_constant():
    ms, _ = modes(model(np.array([[2.6e-113, 10.0], [-10.0, 2.6e-113]])))
    (m,) = ms
    assert m.kind == "marginal" and math.isclose(m.frequency, 10.0) and m.damping == 0.0 and math.isinf(m.time_constant)
    assert m.eigenvalue.real != 0.0  # the eigenvalue itself as computed (the JSON's)
    row = table(model(np.array([[2.6e-113, 10.0], [-10.0, 2.6e-113]]))).splitlines()[1]
    assert row.split()[:7] == ["0", "±", "10j", "10", "0", "inf", "marginal"]


def test_a_zero_eigenvalue_at_round_off_is_marginal_without_damping():
    ms, _ = modes(model(np.array([[-2.2e-135, 0.0], [0.0, -1.0]])))
    zero, stable = ms
    assert zero.kind == "marginal" and zero.frequency == 0.0 and math.isnan(zero.damping)
    assert math.isinf(zero.time_constant)
    assert stable.kind == "stable" and stable.damping == 1.0 and stable.time_constant == 1.0


def test_a_damped_pair_keeps_its_rates_and_the_columns_stay_apart():
    A = np.array([[-1.0, 10.0], [-10.0, -1.0]])
    (m,) = modes(model(A))[0]
    assert m.kind == "stable" and math.isclose(m.damping, 1 / math.sqrt(101)) and m.time_constant == 1.0
    big = table(model(np.array([[-1.23456789e200, 0.0], [0.0, 3.0e150]]))).splitlines()[1:3]
    for row in big:  # eigenvalue, freq, damping, tau, kind, dominant state and its share: 7 fields
        assert len(row.split()) == 7, row
