"""The report's ECOS co-simulation part: the delay its loops model, the speed-up at equal error, the verdict."""

from __future__ import annotations

import math

import numpy as np

from rbcheck.baselines.rigid_body import OneSampleDelay
from rbcheck.workprecision.cosim import CosimRun
from rbcheck.workprecision.cosim_ecos import EcosCosim, EcosRun, ecos_speedup, target_row
from rbcheck.workprecision.references import Reference


def test_one_sample_delay_hands_on_the_laws_output_of_the_sample_before():
    """k = 0: law(x_0); k ≥ 1: law(x_{k−1}) (what a Jacobi master's plant holds over [t_k, t_{k+1}])."""
    law = OneSampleDelay(lambda t, out: {"u": 10.0 * out["x"]})
    got = [law(k * 0.1, {"x": float(k + 1)})["u"] for k in range(4)]
    assert got == [10.0, 10.0, 20.0, 30.0]


def _ref(floor: float = 0.0) -> Reference:
    return Reference(np.zeros(1), np.zeros((1, 3)), np.zeros((1, 4)), "test", floor, 1.0, 0.0)


def _ex(name: str, total: float, cpu: float, err: float) -> CosimRun:
    nan = math.nan
    return CosimRun("Exudyn", name, total, nan, nan, 0.0, err, nan, nan, cpu=cpu)


def test_the_speed_up_takes_for_each_exudyn_loop_the_fastest_ecos_rung_as_accurate():
    """Wall and CPU ratios each over the fastest ECOS rung at least as accurate; a rung less accurate
    than every Exudyn loop never counts; the pair named is that of the smaller ratio."""
    ecos = [EcosRun("fast-bad", 0.001, 0.001, 1e-3, 0, 0), EcosRun("a", 0.02, 0.01, 1e-15, 0, 0),
            EcosRun("b", 0.01, 0.03, 1e-15, 0, 0)]  # fmt: skip
    exudyn = [_ex("x1", 1.0, 0.6, 1e-10), _ex("x2", 0.8, 0.9, 1e-5), _ex("failed", math.nan, math.nan, math.nan)]
    wall, cpu, pair = ecos_speedup(ecos, exudyn, _ref())
    assert math.isclose(wall, 80.0) and math.isclose(cpu, 60.0) and pair == ("a", "x1")
    assert ecos_speedup(ecos[:1], exudyn, _ref()) == (None, None, None)


def test_the_target_is_met_only_when_both_ratios_reach_it():
    res = EcosCosim(4.0, 1e-3, min_speedup=80.0, min_speedup_cpu=40.0, min_pair=("a", "x1"))
    assert "| NOT met |" in target_row(res, 50.0)
    res.min_speedup_cpu = 55.0
    assert "| met |" in target_row(res, 50.0)
    assert "not measured | no ECOS rung" in target_row(EcosCosim(4.0, 1e-3), 50.0)
