"""A free body in a central field (features.central_gravity): rules, equations, invariants, Kepler, scipy.

docs/theory.md §9.7. The potential V = −μ m/r − μ/(2 r³)(tr I − 3 r̂ᵀ I_w r̂) (MacCullagh); the
FMU's force is CasADi's −∂V/∂x_cm and its torque (3μ/r³) ρ̂ × (I ρ̂). Checked here: the scene
rules; the force and torque against the formulas written out by hand in the scipy reference
(rbcheck.baselines.motion.central_field); dE_total/dt = 0 and dL_total/dt = 0 as identities of
the equations; and on the shipped eccentric_orbit (a = 7000 km, e = 0.1, one period, rk8 at
the default tolerance) the invariants, Kepler's ellipse within the quadrupole bound
(rbcheck.closed_forms.kepler.quadrupole_bound) and the scipy reference (rbcheck.checks.central).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from fmu.build.build_fmu import build_fmu
from fmu.drive.instance import FmuError
from fmu.drive.run import run_fmu
from modelsrc.errors import ModelInputError
from modelsrc.features.central_gravity import MU_EARTH
from modelsrc.model import build_model
from modelsrc.nominals import state_nominals
from modelsrc.scene import load_scene
from rbcheck.baselines.motion import central_field, central_potential
from rbcheck.checks import central, registry
from rbcheck.checks.balances import balances, held_run
from rbcheck.closed_forms import kepler
from rbcheck.numerics.rotation_np import quat_to_matrix1

from ..harness.balances import assert_balances_fall_as_simpson
from ..harness.scenes import shared_fmu, write_scene

BASE = """
name = "sat"
[features]
translation = true
central_gravity = true
[body]
principal_moments = [300.0, 500.0, 700.0]
mass = 500.0
[initial]
w_body = [0.0, 0.0, 0.001]
x_cm = [7.0e6, 0.0, 0.0]
v_cm = [0.0, 7500.0, 0.0]
"""

BAD = [
    (BASE.replace("translation = true\n", ""), r"features.central_gravity.*needs features.translation"),
    (BASE.replace("central_gravity = true", "central_gravity = true\ngravity = true") + "[gravity]\ng = [0, 0, 1]\n",
     r"features.central_gravity.*excludes features.gravity"),
    (BASE.replace("translation = true\n", "orbit = true\n") + "[orbit]\nrate = 1e-3\n",
     r"features.central_gravity.*excludes features.orbit"),
    (BASE.replace("central_gravity = true", "central_gravity = true\norbit = true") + "[orbit]\nrate = 1e-3\n",
     r"features.orbit.*excludes.*translation.*central_gravity"),
    (BASE.replace("x_cm = [7.0e6, 0.0, 0.0]", "x_cm = [0.0, 0.0, 0.0]"), r"initial.x_cm.*not at the origin"),
    (BASE.replace("x_cm = [7.0e6, 0.0, 0.0]\n", ""), r"initial.x_cm.*required"),
    (BASE + "[central_gravity]\nmu = 0.0\n", r"central_gravity.mu.*must be > 0, got 0"),
    (BASE + "[central_gravity]\nmu = -1.0\n", r"central_gravity.mu.*must be > 0"),
    (BASE + "[central_gravity]\nmu = nan\n", r"central_gravity.mu.*must be finite"),
    (BASE + "[central_gravity]\nradius = 6.4e6\n", r"central_gravity.radius.*unknown key.*mu"),
    (BASE.replace("central_gravity = true", "central_gravity = false") + "[central_gravity]\nmu = 1.0\n",
     r"field 'central_gravity': given but features.central_gravity"),
    (BASE + '[experiment]\nmethods = ["splitting"]\n', r"experiment.methods.*in a central field they are refused"),
    (BASE + '[experiment]\nmethods = ["exact_free"]\n', r"experiment.methods.*in a central field they are refused"),
]  # fmt: skip


@pytest.mark.parametrize("text,match", BAD)
def test_bad_central_gravity_input_is_refused_with_a_message(tmp_path, text, match):
    with pytest.raises(ModelInputError, match=match):
        load_scene(write_scene(tmp_path, text, "sat"))


def test_mu_defaults_to_earths_and_omega_is_measured_against_the_orbit_rate(tmp_path):
    sc = load_scene(write_scene(tmp_path, BASE, "sat"))
    assert sc.mu == MU_EARTH == 3.986004418e14
    assert not sc.torque_free and sc.conserves_energy and not sc.exact_flow
    # error control (docs/theory.md §5.5): ω against sqrt(μ/r0³) = 1.08e-3 rad/s, not 1 rad/s
    assert state_nominals(sc)["w_body"] == pytest.approx(math.sqrt(MU_EARTH / 7.0e6**3), rel=1e-15)


def _model_at(text_or_scene, tmp_path=None):
    sc = load_scene(write_scene(tmp_path, text_or_scene, "sat")) if isinstance(text_or_scene, str) else text_or_scene
    m = build_model(sc)
    params = [v for v in m.variables if v.kind in (3, 4)]
    return m, [v.name for v in params], [v.start for v in params]


def _evaluate(m, p, x):
    f = m.functions
    d = np.asarray(f["model_derived"](p=p)["d"]).ravel()
    u = np.zeros(m.nu)  # a rotor's motor idle
    xd = np.asarray(f["model_rhs"](x=x, u=u, p=p, d=d)["xdot"]).ravel()
    J = np.asarray(f["model_jac"](x=x, u=u, p=p, d=d)["J"])
    y = np.asarray(f["model_outputs"](x=x, u=u, p=p, d=d)["y"]).ravel()
    outs = [v.name for v in m.variables if v.kind == 5]
    return xd, J, y, outs


def test_force_and_torque_are_the_hand_written_formulas(tmp_path):
    """CasADi's −∂V/∂x_cm and the torque against rbcheck.baselines.motion.central_field (the
    formulas differentiated by hand), at random states of a body whose quadrupole term is not
    small (μ = m = 1, |x| ~ 1 m, tr I = 0.15 kg m²: the terms O(0.1) of the monopole)."""
    sc = load_scene(write_scene(tmp_path, BASE, "sat"))
    m, names, p = _model_at(sc)
    p[names.index("mu")], p[names.index("mass")] = 1.0, 1.0
    I = np.diag([0.03, 0.05, 0.07])
    for k in range(3):
        p[names.index(f"I_principal[{k + 1}]")] = I[k, k]
    rng = np.random.default_rng(7)
    for _ in range(5):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        x = np.concatenate([q, rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)])
        xd, _, y, outs = _evaluate(m, p, x)
        R = quat_to_matrix1(q)
        F, tau = central_field(1.0, 1.0, I, R, x[7:10])
        np.testing.assert_allclose(xd[10:13], F, rtol=0, atol=1e-15 * np.linalg.norm(F))
        w = x[4:7]  # Euler: I ω̇ = τ − ω × I ω
        np.testing.assert_allclose(
            I @ xd[4:7] + np.cross(w, I @ w), tau, rtol=0, atol=1e-15 * (1 + np.linalg.norm(tau))
        )
        V = central_potential(1.0, 1.0, I, R[None], x[None, 7:10])[0]
        E = 0.5 * x[10:13] @ x[10:13] + 0.5 * w @ I @ w + V
        assert y[outs.index("E_total")] == pytest.approx(E, rel=1e-14)
        assert y[outs.index("r_orbit")] == pytest.approx(np.linalg.norm(x[7:10]), rel=1e-15)


WHEEL = """
[rotors.wheel]
axis = [0.6, 0.0, 0.8]
J = 0.01
"""


@pytest.mark.parametrize("rotor", [False, True], ids=["body", "with a wheel"])
def test_energy_and_total_angular_momentum_are_identities_of_the_equations(tmp_path, rotor):
    """d/dt E_total and d/dt L_total along ẋ (CasADi's Jacobian of the outputs times the
    right-hand side) vanish to round-off: force and torque derive from one potential. The
    same μ = m = 1 body as above, where the spin's own rate dL_world/dt = R τ is O(0.1); also
    with a wheel (J = 0.01 kg m², motor idle: its energy and momentum are in E_total, L_total)."""
    text = BASE + (WHEEL if rotor else "")
    sc = load_scene(write_scene(tmp_path, text, "sat"))
    m, names, p = _model_at(sc)
    p[names.index("mu")], p[names.index("mass")] = 1.0, 1.0
    for k, v in enumerate((0.03, 0.05, 0.07)):
        p[names.index(f"I_principal[{k + 1}]")] = v
    rng = np.random.default_rng(11)
    nx = m.nx
    for _ in range(5):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        x = np.concatenate([q, rng.normal(size=3), rng.normal(size=3), rng.normal(size=3), rng.normal(size=m.nx - 13)])
        xd, J, _, outs = _evaluate(m, p, x)
        ydot = J[2 * nx :, :nx] @ xd
        spin = np.linalg.norm(ydot[[outs.index(f"L_world[{k}]") for k in (1, 2, 3)]])
        assert spin > 1e-3  # the gravity-gradient torque turns the spin: the test has something to cancel
        assert abs(ydot[outs.index("E_total")]) < 1e-14
        assert np.linalg.norm(ydot[[outs.index(f"L_total[{k}]") for k in (1, 2, 3)]]) < 1e-14


def test_the_fmu_refuses_a_mu_that_is_not_positive(eccentric_fmu):
    sc = load_scene("eccentric_orbit")
    with pytest.raises(FmuError, match="mu must be > 0"):
        run_fmu(eccentric_fmu, sc, stop_time=10.0, start_values={"mu": 0.0})


@pytest.fixture(scope="module")
def eccentric_fmu(build_dir):
    """The shipped eccentric_orbit's FMU, in the session's build directory (built once, as the
    `fmus` fixture does, without building every other scene)."""
    return shared_fmu(build_dir, "eccentric_orbit")


@pytest.fixture(scope="module")
def measured(eccentric_fmu) -> central.CentralMeasures:
    return central.measure(eccentric_fmu, load_scene("eccentric_orbit"))


# Round-off level for the scene's ~600 rk8 steps: each step's rounding is ~ε = 2.2e-16 of the
# sums E = T + V (|T|, |V| ~ 1.2 |E|) and L = m x × v + spin; as a random walk √600 ε ≈ 5e-15,
# allowing the cancellation of T and V a factor 5: 3e-14 (measured 2.4e-15 and 8.9e-16).
ROUND_OFF = 3e-14


def test_energy_and_total_angular_momentum_are_conserved_to_round_off(measured):
    assert measured.E_drift <= ROUND_OFF, measured.E_drift
    assert measured.L_drift <= ROUND_OFF, measured.L_drift


def test_the_orbit_is_keplers_ellipse_up_to_the_quadrupole(measured):
    """|x_cm − Kepler| along the way and |x_cm(T) − x_cm(0)| after one period stay within the
    quadrupole bound (rbcheck.closed_forms.kepler.quadrupole_bound: 5.6e-4 m here; measured 1.2e-6 and 5.3e-7 m).
    With the inertia scaled by central.QUADRUPOLE_SCALE the deviation from Kepler is the
    quadrupole's (1.2e-3 m, within the bound scaled alike): the FMU's equals the scipy body's
    deviation from a scipy point mass to the errors of the four runs involved (the FMU's, at most
    its distance to scipy plus scipy's own error; the scaled reference's; the point mass's against
    Kepler: 1.0e-6 m in all; measured 1.4e-7 m)."""
    m = measured
    sc = load_scene("eccentric_orbit")
    el = kepler.elements(sc.mu, sc.x0, sc.v0)
    assert el.a == pytest.approx(7.0e6, rel=1e-14) and el.e == pytest.approx(0.1, rel=1e-12)
    assert el.period == pytest.approx(sc.stop_time, rel=1e-14)
    assert m.kepler_dx <= m.bound and m.return_dx <= m.bound, (m.kepler_dx, m.return_dx, m.bound)
    assert m.quadrupole_dx <= central.QUADRUPOLE_SCALE * m.bound, (m.quadrupole_dx, m.bound)
    noise = m.scipy_dx + 2 * m.est_dx + m.point_dx
    assert m.quadrupole_dx > 100 * noise  # the effect is resolved: the comparison below means something
    assert m.effect_dx <= noise, (m.effect_dx, noise)


def test_the_fmu_agrees_with_the_scipy_reference(measured):
    """FMU against scipy's DOP853 at rtol 1e-13 (the same equations written out by hand): within
    twice the reference's own error (its distance to rtol 1e-12), in position and attitude."""
    m = measured
    assert m.scipy_dx <= 2 * m.est_dx, (m.scipy_dx, m.est_dx)
    assert m.scipy_dq <= 2 * m.est_dq, (m.scipy_dq, m.est_dq)
    assert m.scipy_dw <= 1e-12 * math.sqrt(MU_EARTH / 7e6**3), m.scipy_dw


def test_rbfmu_check_runs_the_central_checks_and_the_drifts(eccentric_fmu):
    rep = registry.scene_report(load_scene("eccentric_orbit"), eccentric_fmu, quick=True)
    assert any("Kepler" in r.quantity for r in rep.rows)
    # judged against rbcheck.checks.bounds: the invariants, Kepler within the quadrupole bound, scipy
    assert not rep.failures() and sum(r.judged for r in rep.rows) == 8, registry.format_report(rep)
    assert "FMU vs Exudyn trajectories" in rep.not_applicable
    defaults = rep.drifts[0]
    assert defaults.method == "rk8 (defaults)"
    assert defaults.drifts["E_total"] <= ROUND_OFF and defaults.drifts["L_total"] <= ROUND_OFF, defaults.drifts


# A user's scene: a small body on a fast orbit (μ = 1e3 m³/s², r = 10 m: period 6.3 s, central
# force 100 N, gravity-gradient torque ~3 N m), pushed by a thruster off its centre of mass.
USER_SCENE = """
name = "user_central"
outputs = ["q", "w_body", "w_world", "E_kin", "E_total", "L_world", "x_cm", "v_cm", "p"]
[features]
translation = true
central_gravity = true
[central_gravity]
mu = 1000.0
[body]
principal_moments = [2.0, 3.0, 4.0]
mass = 10.0
[forces.thruster]
point = [0.5, 0.2, 0.0]
frame = "body"
[inputs]
f_thruster = [[0.0, 20.0, 0.0, 5.0], [0.3, 0.0, -10.0, 0.0], [0.6, 0.0, 0.0, 0.0]]
[initial]
w_body = [0.3, -0.2, 1.0]
x_cm = [10.0, 0.0, 0.0]
v_cm = [0.0, 10.0, 1.0]
[experiment]
stop_time = 1.0
step = 0.01
methods = ["rk8"]  # one method keeps the build short
"""


def test_the_input_balances_include_the_central_field(tmp_path):
    """rbfmu check's input balances of a user scene (rbcheck.checks.balances): the work against
    E_total with V, the momentum with the field's force, the angular momentum about the centre of
    mass with its torque. Their residuals are Simpson's rule's per step (H⁵|f⁗|/2880: halving H
    divides them by ~16; measured 16.2, 16.0, 16.0 from 8.9e-10 J, 7.0e-10 N s, 9.2e-11 N m s);
    booked without the field they miss by its impulse (93 N s, 0.85 N m s)."""
    path = write_scene(tmp_path, USER_SCENE, "user_central")
    sc = load_scene(path)
    fmu = build_fmu(sc, tmp_path)
    rep = registry.scene_report(path, fmu, quick=True)
    assert "input balances" not in rep.not_applicable, rep.not_applicable
    rows = {r.quantity: r.fmu for r in rep.rows}
    assert_balances_fall_as_simpson(rows, balances(sc, held_run(fmu, sc, sc.stop_time, step=sc.step / 2)))
    blind = dataclasses.replace(sc, features=sc.features - {"central_gravity"})
    off = balances(blind, held_run(fmu, sc, sc.stop_time))
    assert off.momentum > 10.0 and off.angular_momentum > 0.1, off
    assert rows["momentum balance |dp - int (F + M g) dt|"] < 1e-6 * off.momentum
