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

import numpy as np
import pytest

from modelsrc.scene import load_scene
from rbcheck.checks import registry
from rbcheck.checks.bounds import allowed, vertex_error
from rbcheck.checks.feature_checks import FMU_MARGIN, ROUND_OFF


@pytest.mark.slow
@pytest.mark.parametrize(
    ("scene", "judged"),
    # heavy_top: its nutation bounds u1, u2 too (a refined extremum's own error, bounds.vertex_error);
    # sleeping_top: the two max tilts, the growth rate and the friction's threshold crossing
    [("quadrotor", 13), ("reaction_wheel_slew", 8), ("momentum_bias", 4), ("heavy_top", 10), ("sleeping_top", 4)],
)
def test_the_scene_is_judged_and_passes(fmus, scene, judged):
    rep = registry.scene_report(scene, fmus[scene], quick=True)
    text = registry.format_report(rep)
    assert not rep.failures(), text
    assert sum(r.judged for r in rep.rows) == judged, text
    assert f"{scene}: passed: {judged} row(s) " in text and "within their tolerances" in text


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


def test_the_vertex_error_is_the_third_derivative_times_the_step_cubed():
    # f = a sin(w t): max |f‴| = a w³, to the central difference's O(s^2) (s = span / 4000)
    a, w, dt = 0.5, 3.0, 1e-2
    assert math.isclose(vertex_error(lambda t: a * np.sin(w * t), 2.0, dt), a * w**3 * dt**3, rel_tol=1e-5)
    # and the refined maximum of sampled data is within it
    t = np.arange(0.0, 2.0, dt) + 0.0037
    from rbcheck.numerics.motion_fits import refined_extrema

    _, peaks = refined_extrema(t, a * np.sin(w * t), "max")
    assert abs(peaks[0] - a) <= vertex_error(lambda t: a * np.sin(w * t), 2.0, dt)
