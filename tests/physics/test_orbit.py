"""The circular orbit and the gravity-gradient torque (issue 28): rules, orbit frame, closed forms, invariant, scipy.

docs/theory.md §9. The shipped scene gravity_gradient_boom (a boom along nadir in a 90-min
orbit) is checked with rbcheck.checks.orbit: the pitch libration frequency n√(3(I_x−I_z)/I_y),
the finite-amplitude pitch period 4K(sin²θ₀)/ω_p, the two roll–yaw frequencies of the
linearised equations, the Jacobi integral E_jacobi and the scipy reference
(rbcheck.closed_forms.gravity_gradient). The FMU runs at its defaults: rk8 with error control at the
default tolerance 1e-10 1/s, ω measured against n (modelsrc.nominals).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fmu.drive.instance import FmuError
from fmu.drive.run import run_fmu
from modelsrc.errors import ModelInputError
from modelsrc.methods import METHODS
from modelsrc.model import build_model
from modelsrc.scene import load_scene
from rbcheck.baselines.orbit import reference as scipy_reference
from rbcheck.checks import orbit as ob
from rbcheck.checks import registry
from rbcheck.closed_forms import gravity_gradient as gg

from ..harness.scenes import write_scene

N = 2 * math.pi / 5400
BASE = f"""
name = "sat"
[features]
orbit = true
gravity_gradient = true
[orbit]
rate = {N!r}
[body]
principal_moments = [1000.0, 1020.0, 50.0]
[initial]
w_body = [0.0, {-N!r}, 0.0]
"""

BAD = [
    (BASE.replace(f"rate = {N!r}", "rate = 0.0"), r"orbit.rate.*must be > 0, got 0"),
    (BASE.replace(f"rate = {N!r}", "rate = -1e-3"), r"orbit.rate.*must be > 0"),
    (BASE.replace(f"rate = {N!r}", "rate = nan"), r"orbit.rate.*must be finite"),
    (BASE.replace(f"rate = {N!r}", "rate = inf"), r"orbit.rate.*must be finite"),
    (BASE.replace(f"rate = {N!r}", 'rate = "fast"'), r"orbit.rate.*must be a number"),
    (BASE.replace(f"rate = {N!r}", ""), r"orbit.rate.*required when features.orbit is true"),
    (BASE.replace(f"rate = {N!r}", "rate = 1e-3\nradius = 7e6"), r"orbit.radius.*unknown key.*rate"),
    (BASE.replace("orbit = true", "orbit = false"), r"features.gravity_gradient.*needs features.orbit"),
    (BASE.replace("orbit = true\ngravity_gradient = true", ""), r"field 'orbit': given but features.orbit"),
    (
        BASE.replace("orbit = true", "orbit = true\ntranslation = true"),
        r"features.orbit.*excludes.*translation.*Kepler",
    ),
    (BASE.replace("orbit = true", "orbit = true\ngravity = true"), r"features.orbit.*excludes features.gravity"),
    (BASE.replace("orbit = true", "orbit = true\nprescribed_rate = true"), r"excludes features.prescribed_rate"),
    (BASE + '[experiment]\nmethods = ["splitting"]\n', r"experiment.methods.*in an orbit they are refused"),
    (BASE + '[experiment]\nmethods = ["exact_free"]\n', r"experiment.methods.*in an orbit they are refused"),
]


@pytest.mark.parametrize("text,match", BAD)
def test_bad_orbit_input_is_refused_with_a_message(tmp_path, text, match):
    with pytest.raises(ModelInputError, match=match):
        load_scene(write_scene(tmp_path, text, "sat"))


def test_a_scene_without_orbit_has_no_orbit_variables():
    names = {v.name for v in build_model(load_scene("torque_driven")).variables}
    assert not names & {"orbit_angle", "n_orbit", "E_jacobi", "q_lvlh[1]", "nadir_body[3]"}


def _checks_fail(model, p_values: dict[str, float]) -> list[str]:
    """Texts of model_checks that fail for the scene's start values with `p_values` set."""
    params = [v for v in model.variables if v.kind in (3, 4)]
    p = np.array([p_values.get(v.name, v.start) for v in params], dtype=float)
    x = np.array([v.start for v in model.variables if v.kind == 1], dtype=float)
    code = METHODS[model.default_method].value  # the orbit's check does not depend on the method
    g = np.asarray(model.functions["model_checks"](x=x, p=p, method=code)["g"]).ravel()
    return [t for (t, strict), v in zip(model.checks, g) if not (v > 0 if strict else v >= 0)]


@pytest.mark.parametrize("bad", [0.0, -1e-3, float("nan")])
def test_the_model_refuses_a_rate_that_is_not_positive(bad):
    model = build_model(load_scene("gravity_gradient_boom"))
    assert _checks_fail(model, {}) == []
    assert any("n_orbit must be > 0" in t for t in _checks_fail(model, {"n_orbit": bad}))


def test_the_fmu_refuses_a_rate_that_is_not_positive(fmus):
    sc = load_scene("gravity_gradient_boom")
    with pytest.raises(FmuError, match=r"n_orbit must be > 0"):
        run_fmu(fmus["gravity_gradient_boom"], sc, stop_time=10.0, start_values={"n_orbit": 0.0})


def test_a_body_at_rest_in_lvlh_stays_there(fmus):
    """The equilibrium (body axes = LVLH, ω = −n e_y, §9.1): if the orbit frame turned the
    other way (+n e_y) or the nadir were wrong, the body would leave it at once (ĉ would
    turn at 2n in the body). Over one orbit rk8's error stays at round-off."""
    sc = load_scene("gravity_gradient_boom")
    sv = {"q[1]": 1.0, "q[3]": 0.0, "w_body[2]": -sc.orbit_rate}
    r = run_fmu(fmus["gravity_gradient_boom"], sc, stop_time=5400.0, start_values=sv)
    assert np.max(np.abs(r.vector("nadir_body") - [0.0, 0.0, 1.0])) < 1e-12
    assert np.max(np.abs(r.vector("q_lvlh") - [1.0, 0.0, 0.0, 0.0])) < 1e-12
    assert np.max(np.abs(r.vector("w_lvlh"))) < 1e-12 * sc.orbit_rate
    assert np.max(np.abs(r.vector("rpy_lvlh"))) < 1e-12
    # the orbit angle is n t, and the world-frame nadir of R is (−sin n t, 0, cos n t)
    half = sc.orbit_rate * r.time / 2
    assert np.max(np.abs(r.values["orbit_angle"] - 2 * half)) < 1e-12
    # body = LVLH: q = (cos(nt/2), 0, −sin(nt/2), 0), LVLH turned by −n t about y
    assert np.max(np.abs(r.vector("q") - np.column_stack([np.cos(half), 0 * half, -np.sin(half), 0 * half]))) < 1e-12


def test_jacobi_integral_is_conserved_by_the_equations_also_with_a_wheel(tmp_path):
    """dE_jacobi/dt = ∂E/∂x · ẋ (the FMU's output derivative, CasADi AD) vanishes at random
    states, without and with a rotor (u = 0), with and without the gravity gradient (§9.3):
    an identity of the equations, so zero to round-off of the terms (n² I ~ 1e-3 J)."""
    rng = np.random.default_rng(28)
    wheel = "[rotors.wheel]\naxis = [0.6, 0.0, 0.8]\nJ = 2.0\n"
    for text in (BASE, BASE + wheel, BASE.replace("gravity_gradient = true", "") + wheel):
        model = build_model(load_scene(write_scene(tmp_path, text, "sat")))
        i = [v.name for v in model.variables if v.kind == 5].index("E_jacobi")
        nx = model.nx
        p = np.array([v.start for v in model.variables if v.kind in (3, 4)], dtype=float)
        d = model.functions["model_derived"](p=p)["d"]
        for _ in range(5):
            x = rng.normal(size=nx)
            x[:4] /= np.linalg.norm(x[:4])
            x[4:7] *= N
            x[7:] *= 3.0
            u = np.zeros(model.nu)
            z1 = model.functions["model_output_rates"](x=x, u=u, p=p, d=d, u1=u, u2=u)["z1"]
            E_rate = float(np.asarray(z1).ravel()[nx + i])
            assert abs(E_rate) < 1e-15 * N, (text, E_rate)  # E ~ n² I ~ 1e-3 J: rate ~ n E ~ 1e-6 J/s


@pytest.fixture(scope="module")
def report(fmus):
    """`rbfmu check --scene gravity_gradient_boom --quick`: the scene's report."""
    return registry.scene_report(load_scene("gravity_gradient_boom"), fmus["gravity_gradient_boom"], quick=True)


def test_rbfmu_check_runs_the_orbit_checks_and_says_why_the_generic_ones_do_not_apply(report):
    text = registry.format_report(report)
    assert "pitch libration frequency" in text and "roll-yaw frequency 2" in text
    assert "Jacobi integral" in report.not_applicable["conserved-quantity drift"]
    # judged against rbcheck.checks.bounds (the frequencies, the Jacobi integral, q against scipy and Exudyn)
    assert not report.failures() and sum(r.judged for r in report.rows) == 8, text
    assert "rbcheck.exudyn.orbit" in report.not_applicable["FMU vs Exudyn trajectories"]
    assert "E_jacobi" in report.not_applicable["input balances"]


def test_small_pitch_librations_at_the_closed_form_frequency(report):
    """ω_p = n√(3(I_x−I_z)/I_y) (§9.5) from a sinusoid fitted to 5 periods started at θ₀ = 1e-4
    rad. The pendulum lowers the frequency by m/4 = sin²θ₀/4 = 2.5e-9 relative: the fit
    resolves it (measured −2.4991e-9), so it is compared with the exact 2π/(4K(m)/ω_p) to
    1e-10 (measured 9e-13: rk8 at tolerance 1e-10 1/s, phase error ≲ 1e-10 per libration)."""
    m = report.details["orbit"]
    sc = load_scene("gravity_gradient_boom")
    exact = 2 * math.pi / gg.pitch_period(sc.orbit_rate, np.diag(sc.inertia), ob.SMALL)
    rel = m.pitch_small / m.pitch_small_closed - 1
    assert abs(rel + math.sin(ob.SMALL) ** 2 / 4) < 1e-10, rel
    assert abs(m.pitch_small / exact - 1) < 1e-10


def test_finite_pitch_period_is_the_pendulums(report):
    """4K(sin²θ₀)/ω_p at θ₀ = 0.5 rad (6 % longer than the small period, §9.5), from zero
    crossings over 3 periods, each located by a cubic through 4 samples 10 s apart: its error
    ~(ωh)⁴/ω ≈ 1e-7 s per crossing; measured 1.7e-13 relative. Bound 1e-9 relative (3e-6 s)."""
    m = report.details["orbit"]
    assert m.pitch_period * m.pitch_small_closed / (2 * math.pi) > 1.05  # not the small-amplitude period
    assert abs(m.pitch_period / m.pitch_period_closed - 1) < 1e-9


def test_roll_yaw_frequencies_are_the_linearised_ones(report):
    """The roots of Ω⁴ − (1 + 3k_R + k_R k_Y) n²Ω² + 4 k_R k_Y n⁴ (§9.6), fitted (two sinusoids
    shared by roll and yaw, start guess from the DFT) to a run from roll = yaw = 1e-4 rad:
    the neglected nonlinear terms shift them by O(1e-4²) = 1e-8 relative (measured −1.6e-8 and
    −1.8e-9); bound 5e-8."""
    m = report.details["orbit"]
    for f, c in zip(m.roll_yaw, m.roll_yaw_closed):
        assert abs(f / c - 1) < 5e-8, (f, c)


def test_jacobi_integral_holds_to_round_off_at_the_scene_defaults(report):
    """max|E_J − E_J(0)| over the scene's 3 orbits (1620 doSteps) relative to n² tr I: round-off
    (measured 2.5e-14; the terms are ~1e-3 J, each step adds a few ulps); bound 1e-13. The FMU's
    E_jacobi(0) equals numpy's evaluation of the formula (rbcheck.closed_forms.gravity_gradient) to 1e-15."""
    m = report.details["orbit"]
    assert m.jacobi_drift < 1e-13
    assert m.jacobi_formula < 1e-15


def test_fmu_agrees_with_the_scipy_reference(report):
    """The scene's run against DOP853 at rtol 1e-13 with the nadir explicit in time (an
    independent numpy right-hand side): measured 7.3e-13 in q and 2.6e-12 n in ω, below the
    reference's own error estimate (its distance to rtol 1e-12, measured 7.6e-12); bound 5e-11."""
    m = report.details["orbit"]
    assert m.scipy_dq < 5e-11 and m.scipy_dw < 5e-11
    assert m.est_dq < 5e-11


def test_fmu_agrees_with_exudyn(report):
    """Exudyn RK67 at h = 10 s (a free body whose load user function evaluates the torque from
    the stage's orientation, rbcheck.exudyn.orbit; its error ~1e-13 by its measured sixth
    order) over one orbit (quick): measured 2.0e-13 in q, 1.5e-13 n in ω; and Exudyn against
    scipy as close as the FMU (5.7e-13). Bound 5e-12, the FMU's error-control level."""
    m = report.details["orbit"]
    assert m.fmu_exudyn_dq < 5e-12 and m.fmu_exudyn_dw < 5e-12
    assert m.exudyn_dq < 5e-11 and m.exudyn_dw < 5e-11


def test_the_rigid_body_scipy_baseline_has_the_gravity_gradient(fmus):
    """rbcheck.baselines.rigid_body (the work-precision report's scipy baseline) with the orbit's torque
    agrees with rbcheck.baselines.orbit's reference (both DOP853, rtol 1e-13) over one orbit."""
    from rbcheck.baselines.motion import integrate

    sc = load_scene("gravity_gradient_boom")
    grid = 60.0 * np.arange(91)
    tr = integrate(sc, grid, "DOP853", rtol=1e-13, atol=1e-16)
    q, w = scipy_reference(sc.orbit_rate, np.diag(sc.inertia), sc.q0, sc.w0, grid)
    assert np.max(np.abs(tr.q - q)) < 1e-11
    assert np.max(np.abs(tr.w_body - w)) < 1e-11 * sc.orbit_rate
