"""Tests of the report's error-control part: error against tolerance, its cost against fixed steps, the defaults."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from modelsrc.scene import load_scene
from rbcheck.numerics.rotation_np import quat_mul, quat_to_matrix, rotation_angle_between
from rbcheck.workprecision.cli import main
from rbcheck.workprecision.config import Config
from rbcheck.workprecision.references import make_reference
from rbcheck.workprecision.tolerance import tolerance_scene
from rbcheck.workprecision.tolerance_defaults import TARGET_DRIFT, TARGET_ERROR, fast_spin


def test_error_falls_with_the_tolerance_and_stays_below_tolerance_times_T(fmus):
    """rk4 on symmetric_free (closed-form reference, its own error ~6e-15) at tolerances
    1e-5 and 1e-9 per second. The step is chosen so that the order-3 estimate C h^4 equals
    tolerance·h, h ∝ tolerance^(1/3), and the order-4 solution's error falls like
    h^4 ∝ tolerance^(4/3): 1e4 in tolerance is ~2e5 in error (measured 1.9e5); asserted
    ≥ 1e3, room for the pre-asymptotic loose end. The estimate is that of the less
    accurate order-3 companion, so the error stays below tolerance·T (measured ratios
    0.05 and 0.003)."""
    cfg = Config.quick(("symmetric_free",))
    cfg.tolerances = (1e-5, 1e-9)
    res = tolerance_scene("symmetric_free", fmus["symmetric_free"], cfg, None, methods=["rk4"])
    assert res.T == 10.0 and not res.shortened and res.n_comm == 10
    assert res.ref.source.startswith("closed form") and res.ref.floor < 1e-13
    (m,) = res.methods
    assert m.method == "rk4" and [p.tolerance for p in m.controlled.points] == [1e-5, 1e-9]
    loose, tight = m.controlled.points
    assert tight.accepted > loose.accepted > 0 and tight.work == tight.accepted + tight.rejected
    assert tight.err < loose.err / 1e3
    ratios = m.ratios(res.T, res.ref.floor)
    assert all(ok and 0 < r <= 1.0 for _, r, ok in ratios), ratios
    band = res.band()
    assert band is not None and band[0] == min(r for _, r, _ in ratios) and band[1] == max(r for _, r, _ in ratios)
    # the fixed-step ladder ran (tolerance 0, h_max rungs) and the cost at equal error is defined
    assert m.fixed.points and all(p.tolerance == 0 and p.h_max > 0 for p in m.fixed.points)
    assert len(m.cost_ratios()) == 2


def test_a_method_without_error_control_is_refused(fmus):
    with pytest.raises(ValueError, match="'splitting' has no error control in scene symmetric_free; allowed: rk4"):
        tolerance_scene("symmetric_free", fmus["symmetric_free"], Config.quick(), None, methods=["splitting"])


def test_fast_spin_at_the_defaults_meets_its_target(fmus):
    """free_asymmetric's body near its major axis at 1e4 rad/s, communication step 1e-2 s
    for 0.1 s: the default exact_free is exact up to round-off of the angle (ε·1e4·0.1 ~
    2e-13 rad), so 1e-8 and 1e-9 are met with margin; rk8 at the default tolerance 1e-10
    per second keeps ~1e-11 over 0.1 s."""
    cfg = Config.quick()
    cfg.spin_rates, cfg.spin_bodies = (1e4,), {"near the major axis": (1e-3, 0.0, 1.0)}
    runs = fast_spin(fmus["free_asymmetric"], cfg, None)
    assert [r.setting for r in runs] == ["defaults (exact_free)", "rk8, tolerance 1e-10"]
    for r in runs:
        p = r.point
        assert r.omega_scale == pytest.approx(1e4)
        assert p.err <= TARGET_ERROR and p.drift_E <= TARGET_DRIFT and p.drift_L <= TARGET_DRIFT, (r.setting, p)
        assert r.met and p.accepted > 0
    assert runs[0].point.accepted == 10  # exact_free: one step per communication step


def test_prescribed_rate_reference_is_the_uniform_rotation():
    """skewed_bar holds ω (body) constant: the closed form must solve q̇ = ½ q ⊗ (0, ω)
    (docs/theory.md §1); scipy DOP853 at rtol 1e-12 over 2 s (20 rad) agrees to ~1e-11."""
    sc = load_scene("skewed_bar")
    grid = np.linspace(0.0, 2.0, 11)
    ref = make_reference(sc, grid)
    w = np.asarray(sc.w0, float)
    sol = solve_ivp(
        lambda t, q: 0.5 * quat_mul(q, np.r_[0.0, w]),
        (0, 2),
        np.asarray(sc.q0, float),
        t_eval=grid,
        rtol=1e-12,
        atol=1e-14,
        method="DOP853",
    )
    for k in range(grid.size):
        assert rotation_angle_between(quat_to_matrix(sol.y[:, k]), quat_to_matrix(ref.q[k])) < 1e-10
    assert np.all(ref.w == w) and math.isclose(ref.omega_scale, float(np.max(np.abs(w))))


@pytest.mark.slow
def test_the_part_runs_alone_from_the_command(tmp_path):
    """`--parts tolerance` runs only the error-control part (one FMU built) and writes its
    section and figure."""
    out = tmp_path / "report"
    assert main(["--quick", "--scenes", "symmetric_free", "--parts", "tolerance", "--out", str(out)]) == 0
    text = (out / "report.md").read_text()
    assert (
        "## Error control: achieved error against tolerance" in text and "\n## symmetric_free\n" not in text
    )  # no batch part
    assert "### symmetric_free: error against tolerance" in text and "### Every scene at its defaults" in text
    assert (out / "tolerance.png").stat().st_size > 10_000


def test_retime_keeps_the_fastest_round_and_spares_expensive_runs():
    """The cost ratio's wall times (tolerance.retime): every run of both ladders is timed in
    turn, round after round, each keeping its fastest time (its first measurement
    included); a run stops taking part once its timings add up to RETIME_BUDGET, so an
    expensive rung is not timed RETIME_ROUNDS times. The driver here is a stand-in that
    records what it is asked to run and returns scripted times."""
    from rbcheck.workprecision.measures import Line
    from rbcheck.workprecision.tolerance import RETIME_BUDGET, RETIME_ROUNDS, ControlPoint, retime

    class Driver:
        def __init__(self):
            self.tolerance = None
            self.calls: list[tuple[float, float]] = []

        def run(self, method, h_max, grid, record):
            assert method == "rk4" and not record
            self.calls.append((self.tolerance, h_max))
            n = sum(1 for c in self.calls if c == (self.tolerance, h_max))
            if h_max == 0.5:  # the expensive rung: 0.2 s per run
                return 0.2, None
            return (0.010 if n == 3 else 0.012), None  # the third round is the fastest

    def point(tol, h_max, wall):
        return ControlPoint("p", tol or h_max, wall, 1e-6, 0, 0, tolerance=tol, h_max=h_max)

    ctl, fix = Line("ctl", "FMU"), Line("fix", "FMU")
    ctl.points = [point(1e-6, 0.0, 0.011), point(1e-8, 0.0, 0.009)]
    fix.points = [point(0.0, 0.5, 0.25), point(0.0, 0.1, 0.02)]
    drv = Driver()
    retime(drv, "rk4", (ctl, fix), np.linspace(0.0, 1.0, 11))
    assert [p.wall for p in ctl.points] == [0.010, 0.009]  # the fastest: a round's, or the first
    assert fix.points[0].wall == 0.2 and fix.points[1].wall == 0.010
    # controlled runs with their tolerance and no cap, fixed ones with tolerance 0 and their h_max
    assert drv.calls.count((1e-6, 0.0)) == RETIME_ROUNDS and drv.calls.count((0.0, 0.1)) == RETIME_ROUNDS
    assert drv.calls.count((0.0, 0.5)) == math.ceil(RETIME_BUDGET / 0.2)


def test_a_missed_default_run_is_explained_from_what_it_measured():
    """The report's note under the default-settings tables (tolerance_report._miss_note):
    the round-off floor is named only where tolerance·h fell below it, the conditioning
    only where the reference's own error says the flow amplifies (κ = floor / ε), and the
    defaults only where they met the target on the same case."""
    from modelsrc.methods import DEFAULT_TOLERANCE, ESTIMATE_FLOOR
    from rbcheck.workprecision.tolerance import EPS, ControlPoint
    from rbcheck.workprecision.tolerance_defaults import DefaultRun
    from rbcheck.workprecision.tolerance_report import _miss_note

    def run(setting, err, steps, floor, tol=DEFAULT_TOLERANCE, defaults=False):
        p = ControlPoint("tol", tol, 0.1, err, err, err, accepted=steps, tolerance=tol)
        return DefaultRun("racket", setting, 1.0, 0.01, "closed form", floor, 1e5, p, defaults)

    # 1e-10 · 1e-6 s = 1e-16 ... below the floor from 1e6 steps per second up
    n_floor = math.ceil(DEFAULT_TOLERANCE / ESTIMATE_FLOOR) * 2
    missed = run("rk8, tolerance 1e-10", 5e-8, n_floor, 2e5 * EPS)
    fine = run("defaults (exact_free)", 3e-9, 100, 2e5 * EPS, tol=0.0, defaults=True)
    assert not missed.met and fine.met
    note = _miss_note(missed, [fine, missed])
    assert "below the floor" in note and "2e+05" in note and "defaults meet" in note
    few_steps = run("rk8, tolerance 1e-10", 5e-8, 1000, 10 * EPS)
    note = _miss_note(few_steps, [few_steps])
    assert "floor" not in note and "amplifies" not in note and "defaults" not in note
