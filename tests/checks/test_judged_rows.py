"""`rbfmu check` judges every shipped scene against a-priori bounds (rbcheck.checks.bounds); nothing judged is no pass.

The gyrostat, orbit, quadrotor, slew and bearing scenes had rows without a tolerance only, so
that `rbfmu check` printed "no failures" having judged nothing for them. Here: the scenes
not covered by a report test elsewhere pass with their rows judged, a report whose rows carry
no tolerance fails with the reason, and the bound grows with what the FMU's error control
allows (tolerance · T, the quantity's size, a reference's error).
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from modelsrc.scene import load_scene
from rbcheck.checks import registry
from rbcheck.checks.bounds import allowed
from rbcheck.checks.feature_checks import FMU_MARGIN, ROUND_OFF


@pytest.mark.slow
@pytest.mark.parametrize(("scene", "judged"), [("quadrotor", 13), ("reaction_wheel_slew", 8), ("momentum_bias", 4)])
def test_the_scene_is_judged_and_passes(fmus, scene, judged):
    rep = registry.scene_report(scene, fmus[scene], quick=True)
    text = registry.format_report(rep)
    assert not rep.failures(), text
    assert sum(r.judged for r in rep.rows) == judged, text
    assert f"{scene}: passed: {judged} row(s) within their tolerances" in text


def test_a_report_that_judged_nothing_fails():
    rows = [registry.Row("peak rate", "rad/s", 1.0, float("nan")), registry.Row("a - b", "m", 1e-9, float("nan"), 0.0)]
    rep = registry.SceneReport("s", "", rows, None, [], {}, 0.0)
    (why,) = rep.failures()
    assert "nothing was checked against a bound" in why and "tolerance 0" in why
    assert "s: FAILED (1 reason(s)" in registry.format_report(rep)
    rows[1].tol = 1e-8  # one judged row that passes: the report passes
    assert not rep.failures()
    rows[1].tol = 1e-10  # and that fails: it fails for that row
    assert rep.failures() == ["a - b: measured 1.000e-09 m, allowed 1.000e-10 m"]


def test_the_bound_is_what_the_error_control_allows():
    sc = load_scene("free_asymmetric")
    T, S = 30.0, 2.0
    base = (FMU_MARGIN * sc.tolerance * T + ROUND_OFF) * S
    assert allowed(sc, T, S) == pytest.approx(base, rel=1e-15)
    assert allowed(sc, T, -S, model=1e-8, reference=1e-9) == pytest.approx(base + 1e-8 * S + 3e-9, rel=1e-15)
    assert allowed(sc, 2 * T, S) > allowed(sc, T, S)
    assert math.isnan(allowed(dataclasses.replace(sc, tolerance=0.0), T, S))  # fixed steps: no a-priori bound
