"""The sub-step limit's norms: largest_magnitude is CasADi's norm_inf bit for bit, induced_inf_norm the row-sum norm.

modelsrc/model_functions.py, largest_magnitude and induced_inf_norm (model_rate's ‖∂f/∂x‖∞, the
largest row sum, which bounds the spectral radius); docs/theory.md §5.4 (the rate that sizes the
substeps); issue 35 (a doStep evaluates it once; both generated without fmax calls).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from modelsrc.model_functions import induced_inf_norm, largest_magnitude


def _pair(m: ca.SX, x: ca.SX) -> ca.Function:
    return ca.Function("f", [x], [ca.vertcat(largest_magnitude(m), ca.norm_inf(m))])


def test_largest_magnitude_is_norm_inf_bit_for_bit_with_repeated_entries_nan_and_inf():
    x = ca.SX.sym("x", 4)
    # repeated entries (as a Jacobian has them: 0.5 ω in several places), a product, a zero
    m = ca.blockcat([[0.5 * x[0], x[1] * x[2], 0], [0.5 * x[0], -x[3], x[1] * x[2]], [x[3] - x[0], 0.5 * x[0], 0]])
    f = _pair(m, x)
    rng = np.random.default_rng(3)
    for _ in range(200):
        v = rng.normal(size=4) * 10.0 ** rng.integers(-5, 6, size=4)
        new, ref = np.asarray(f(v)).ravel()
        assert new == ref
    for v in ([np.nan, 1.0, 2.0, 3.0], [1.0, np.inf, 2.0, 0.0], [0.0, 0.0, 0.0, 0.0], [1.0, np.nan, 2.0, 5.0]):
        new, ref = np.asarray(f(np.array(v))).ravel()
        assert new == ref or (np.isnan(new) and np.isnan(ref)), (v, new, ref)


def test_largest_magnitude_is_generated_without_fmax_and_takes_each_entry_once():
    x = ca.SX.sym("x", 3)
    m = ca.blockcat([[0.5 * x[0], 0.5 * x[0]], [x[1] * x[2], x[1] * x[2]]])
    code = ca.CodeGenerator("rate_norm_test")
    code.add(ca.Function("r", [x], [largest_magnitude(m)]))
    text = code.dump()
    body = text[text.index("static int casadi_f0") :]
    assert "fmax" not in body
    assert body.count("fabs(") == 2  # two distinct entries, each once
    assert ca.norm_inf(ca.SX(0, 0)).is_zero() and largest_magnitude(ca.SX(2, 2)).is_zero()


def test_induced_inf_norm_is_the_largest_row_sum_and_bounds_the_spectral_radius():
    x = ca.SX.sym("x", 4)
    m = ca.blockcat([[0.5 * x[0], x[1] * x[2], 0], [0.5 * x[0], -x[3], x[1] * x[2]], [x[3] - x[0], 0.5 * x[0], 0]])
    f = ca.Function("f", [x], [induced_inf_norm(m), m])
    rng = np.random.default_rng(5)
    for _ in range(200):
        v = rng.normal(size=4) * 10.0 ** rng.integers(-5, 6, size=4)
        norm, mat = f(v)
        mat = np.asarray(mat)
        assert float(norm) == pytest.approx(np.linalg.norm(mat, np.inf), rel=1e-15)
        assert float(norm) >= np.max(np.abs(np.linalg.eigvals(mat))) * (1 - 1e-12)
    ones = ca.Function(
        "g", [x], [induced_inf_norm(ca.DM.ones(2, 2) * x[0]), largest_magnitude(ca.DM.ones(2, 2) * x[0])]
    )
    assert [float(v) for v in ones(np.array([1.0, 0, 0, 0]))] == [2.0, 1.0]  # the spectral radius is 2
    code = ca.CodeGenerator("row_norm_test")
    code.add(ca.Function("r", [x], [induced_inf_norm(m)]))
    text = code.dump()
    assert "fmax" not in text[text.index("static int casadi_f0") :]
