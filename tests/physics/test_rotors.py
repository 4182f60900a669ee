"""The rotors (issue 28, torque mode): scene rules, conservation laws, the dual-spin closed forms and Exudyn.

docs/theory.md §8. The shipped scene dual_spin (a wheel along the intermediate axis) is
checked with rbcheck.checks.gyrostat: world angular momentum with and without motor torque,
the energy balance with the motor power, the nutation frequency and the growth rate of the
linearised gyrostat (rbcheck.closed_forms.dual_spin), and the jointed Exudyn model (rbcheck.exudyn.rotors).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import simpson

from fmu.drive.instance import FmuError
from fmu.drive.run import run_fmu
from modelsrc.errors import ModelInputError
from modelsrc.model import build_model
from modelsrc.scene import load_scene
from modelsrc.scene_limits import MAX_ROTORS
from rbcheck.checks import gyrostat as gy
from rbcheck.checks import registry
from rbcheck.closed_forms import dual_spin as ds

from ..harness.scenes import write_scene

BASE = """
name = "gyro"
[body]
principal_moments = [350.0, 200.0, 300.0]
[initial]
w_body = [0.01, 0.0, 1.0]
"""
WHEEL = """
[rotors.wheel]
axis = [0.0, 0.0, 1.0]
J = 1.0
"""


def test_a_scene_without_rotors_has_no_rotor_variables():
    names = [v.name for v in build_model(load_scene("free_asymmetric")).variables]
    assert not any(n.startswith(("Omega", "u_", "J_")) for n in names)


def test_the_rotor_variables_and_the_default_method():
    sc = load_scene("dual_spin")
    assert sc.method == "rk8" and "exact_free" not in sc.methods and "splitting" not in sc.methods
    assert not sc.exact_flow  # the exact flow is the rigid body's
    m = build_model(sc)
    kinds = {v.name: (v.kind.name, v.unit, v.start) for v in m.variables}
    assert kinds["Omega_wheel"] == ("STATE", "rad/s", 100.0)
    assert kinds["u_wheel"] == ("INPUT", "N.m", 0.0)
    assert kinds["J_wheel"][1:] == ("kg.m2", 1.0)
    assert kinds["Omega_abs_wheel"][:2] == ("OUTPUT", "rad/s") and kinds["h_wheel"][:2] == ("OUTPUT", "N.m.s")
    assert m.nx == 8 and m.nu == 1


def test_the_equations_against_the_hand_derivation():
    """ω̇, Ω̇, E and L of the generated functions at a generic state, against numpy: a tilted
    wheel axis, a full inertia, a torque input and a motor torque (docs/theory.md §8.1, §8.2)."""
    text = """
name = "gyro_full"
outputs = ["q", "w_body", "E_kin", "L_body"]
[features]
torque_body = true
[body]
inertia = [[5.0, 0.3, -0.2], [0.3, 4.0, 0.1], [-0.2, 0.1, 3.0]]
[rotors.a]
axis = [0.6, 0.0, 0.8]
J = 0.5
[rotors.b]
axis = [0.0, 1.0, 0.0]
J = 0.2
[initial]
w_body = [0.3, -0.2, 0.5]
Omega_a = 7.0
Omega_b = -3.0
"""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        sc = load_scene(write_scene(Path(tmp), text, "gyro_full"))
    m = build_model(sc)
    f = m.functions
    p = np.array([v.start for v in m.variables if v.kind.name in ("PARAM_FIXED", "PARAM_TUNABLE")], dtype=float)
    d = np.asarray(f["model_derived"](p=p)["d"]).ravel()
    q = np.array([0.9, 0.1, -0.3, 0.2])
    q /= np.linalg.norm(q)
    w, Om = np.array([0.3, -0.2, 0.5]), np.array([7.0, -3.0])
    x = np.concatenate([q, w, Om])
    tau, u = np.array([0.1, -0.4, 0.2]), np.array([0.7, -0.3])  # u order: tau_body, then u_a, u_b
    uu = np.concatenate([tau, u])
    xdot = np.asarray(f["model_rhs"](x=x, u=uu, p=p, d=d)["xdot"]).ravel()
    I = np.asarray(sc.inertia)
    g = np.array([[0.6, 0.0, 0.8], [0.0, 1.0, 0.0]])
    J = np.array([0.5, 0.2])
    h = (J * Om) @ g
    M = I - sum(J[k] * np.outer(g[k], g[k]) for k in range(2))
    w_dot = np.linalg.solve(M, tau - np.cross(w, I @ w + h) - u @ g)
    Om_dot = u / J - g @ w_dot
    assert np.allclose(xdot[4:7], w_dot, rtol=0, atol=1e-14)
    assert np.allclose(xdot[7:9], Om_dot, rtol=0, atol=1e-13)
    # the same ω̇ from the balance of the whole: d/dt(Iω + h) + ω × (Iω + h) = τ
    assert np.allclose(I @ w_dot + (J * Om_dot) @ g + np.cross(w, I @ w + h), tau, rtol=0, atol=1e-13)
    y = np.asarray(f["model_outputs"](x=x, u=uu, p=p, d=d)["y"]).ravel()
    names = [v.name for v in m.variables if v.kind.name == "OUTPUT" and not v.name.startswith(("q[", "w_body["))]
    out = dict(zip(names, y))
    # E: rest of the body + each rotor's ½ J (g·ω + Ω)²  ==  ½ ωᵀIω + Σ J Ω g·ω + ½ Σ J Ω²
    E = 0.5 * w @ M @ w + 0.5 * np.sum(J * (g @ w + Om) ** 2)
    assert out["E_kin"] == pytest.approx(E, rel=1e-14)
    assert np.allclose([out[f"L_body[{i}]"] for i in (1, 2, 3)], I @ w + h, rtol=1e-14)
    assert out["Omega_abs_a"] == pytest.approx(0.6 * 0.3 + 0.8 * 0.5 + 7.0, rel=1e-15)
    assert out["h_b"] == pytest.approx(0.2 * (-0.2 - 3.0), rel=1e-15)


# (scene text, what the error must say)
BAD = [
    (BASE + WHEEL.replace("[0.0, 0.0, 1.0]", "[0.0, 0.0, 0.0]"), r"rotors.wheel.axis.*unit vector.*\|axis\| = 0"),
    (BASE + WHEEL.replace("[0.0, 0.0, 1.0]", "[0.0, 0.0, 1.01]"), r"rotors.wheel.axis.*within 1e-06 of 1.*1.01"),
    (BASE + WHEEL.replace("[0.0, 0.0, 1.0]", "[0.0, nan, 1.0]"), r"rotors.wheel.axis\[2\].*must be finite"),
    (BASE + WHEEL.replace("[0.0, 0.0, 1.0]", "[0.0, 0.0, inf]"), r"rotors.wheel.axis\[3\].*must be finite"),
    (BASE + WHEEL.replace("J = 1.0", "J = 0.0"), r"rotors.wheel.J.*must be in \[1e-100, 1e\+100\].*got 0"),
    (BASE + WHEEL.replace("J = 1.0", "J = -2.0"), r"rotors.wheel.J.*must be in \[1e-100, 1e\+100\].*got -2"),
    (BASE + WHEEL.replace("J = 1.0", "J = 300.0"), r"rotors.wheel.J.*'wheel'.*smallest eigenvalue 0 kg m\^2"),
    (BASE + WHEEL + WHEEL.replace("wheel", "w2").replace("J = 1.0", "J = 299.5"), r"rotors.w2.J.*'w2'.*-0.5"),
    (BASE + WHEEL + WHEEL, r"not valid TOML"),  # a rotor named twice
    (BASE + WHEEL.replace("J = 1.0", "J = 1.0\nmass = 2.0"), r"rotors.wheel.*axis = \[x, y, z\].*J"),
    (BASE + WHEEL.replace("wheel", "1x"), r"rotors.1x.*identifier"),
    (BASE + WHEEL.replace("wheel", "max"), r"rotors.max.*not one of last, max, next"),
    (BASE + WHEEL + WHEEL.replace("wheel", "abs_wheel"), r"rotors.abs_wheel.*nor starting with abs_ or dot_"),
    (BASE + WHEEL + "[inputs]\nu_wheel = [1.0, 0.0, 0.0]\n", r"inputs.u_wheel.*must be a number"),
    (BASE + WHEEL + "[inputs]\nu_wheel = [[0.0, 1.0, 2.0]]\n", r"inputs.u_wheel\[1\].*list of 2 numbers"),
    (
        BASE + WHEEL + "[inputs]\nu_wheel = { amplitude = [1.0], omega = 2.0 }\n",
        r"inputs.u_wheel.amplitude.*must be a number",
    ),
    (BASE + WHEEL.replace("J = 1.0", 'J = 1.0\nmode = "rpm"'), r"rotors.wheel.mode.*torque, speed.*'rpm'"),
    (
        BASE + "Omega_wheel = 3.0\n" + WHEEL.replace("J = 1.0", 'J = 1.0\nmode = "speed"'),
        r"initial.Omega_wheel.*speed mode: Omega_wheel is an input",
    ),
    (
        BASE + WHEEL.replace("J = 1.0", 'J = 1.0\nmode = "speed"') + "[inputs]\nOmega_wheel = [[0.0, 1.0]]\n",
        r"inputs.Omega_wheel.*not a table",
    ),
    (
        BASE + WHEEL.replace("J = 1.0", 'J = 1.0\nmode = "speed"') + "[inputs]\nu_wheel = 1.0\n",
        r"inputs.u_wheel.*unknown key",
    ),
    (BASE + WHEEL + "[inputs]\nOmega_wheel = 1.0\n", r"inputs.Omega_wheel.*unknown key"),  # a torque-mode state
    (
        BASE + WHEEL.replace("J = 1.0", "J = 1.0\nposition = [1.0, 0.0, 0.0]"),
        r"rotors.wheel.position.*needs mode = \"speed\"( or \"command\")?, "
        r"features.translation.*'torque', no translation",
    ),
    (BASE + WHEEL.replace("wheel", "dot_w"), r"rotors.dot_w.*nor starting with abs_ or dot_"),
    (BASE + "Omega_wheel = 3.0\n", r"initial.Omega_wheel.*unknown key"),  # no such rotor
    (BASE + "Omega_wheel = true\n" + WHEEL, r"initial.Omega_wheel.*must be a number"),
    (BASE + WHEEL + '[experiment]\nmethods = ["splitting"]\n', r"experiment.methods.*with rotors they are refused"),
    (BASE + WHEEL + "[features]\nprescribed_rate = true\n", r"rotors.*exclude features.prescribed_rate"),
    (
        BASE + "".join(WHEEL.replace("wheel", f"r{k}").replace("J = 1.0", "J = 0.01") for k in range(MAX_ROTORS + 1)),
        rf"field 'rotors': {MAX_ROTORS + 1} rotors; at most {MAX_ROTORS}",
    ),
]


@pytest.mark.parametrize("text,match", BAD)
def test_bad_rotor_input_is_refused_with_a_message(tmp_path, text, match):
    with pytest.raises(ModelInputError, match=match):
        load_scene(write_scene(tmp_path, text, "gyro"))


def test_an_axis_within_1e_9_of_unit_length_is_normalised(tmp_path):
    sc = load_scene(write_scene(tmp_path, BASE + WHEEL.replace("[0.0, 0.0, 1.0]", "[0.0, 0.0, 1.0000000005]")))
    assert sc.rotors["wheel"].axis[2] == 1.0


def test_the_fmu_refuses_rotor_parameters_that_break_the_inertia(fmus):
    sc = load_scene("dual_spin")
    with pytest.raises(FmuError, match=r"J_wheel must be in \[1e-100, 1e\+100\]"):
        run_fmu(fmus["dual_spin"], sc, stop_time=0.1, start_values={"J_wheel": 0.0})
    with pytest.raises(FmuError, match=r"I - sum J g g\^T .* must be positive definite"):
        run_fmu(fmus["dual_spin"], sc, stop_time=0.1, start_values={"J_wheel": 300.0})


def test_world_angular_momentum_is_conserved_with_and_without_motor_torque(fmus):
    """(a) rk8 at the default tolerance 1e-10 1/s; its truncation error at these steps is
    below round-off (measured 1.8e-15 and 8.5e-16 relative over 10 s, 200 communication
    steps): asserted below 1e-13, ~450 ε, round-off of a few ε per step."""
    c = gy.momentum_conservation(fmus["dual_spin"], load_scene("dual_spin"))
    print(c)
    assert c.rel_drift_free < 1e-13 and c.rel_drift_driven < 1e-13
    assert c.wheel_rate_change > 5.0  # the motor torque did act: ∫u/J dt = 8 rad/s of schedule


def test_energy_changes_by_the_motor_work(fmus):
    """dE/dt = Σ u Ω (docs/theory.md §8.2): E(T) − E(0) = ∫ u Ω dt with u = 2 N·m held, Ω at the
    communication points integrated by Simpson (error (ΔΩ̈ H⁴/180)·T ~ 1e-10 of the work)."""
    sc = load_scene("dual_spin")
    r = run_fmu(fmus["dual_spin"], sc, stop_time=2.0, input_fn=lambda t, y: {"u_wheel": 2.0})
    E, Om = r.values["E_kin"], r.values["Omega_wheel"]
    work = simpson(2.0 * Om, x=r.time)
    assert E[-1] - E[0] == pytest.approx(work, rel=1e-9)
    assert work > 400.0


def test_nutation_frequency_matches_the_closed_form(fmus):
    """(b) ε = 1e-5 rad/s: the nonlinear shift O(ε²) ~ 1e-10, the zero crossings' cubic
    interpolation at Δ = 0.05 s, ν = 0.378 rad/s: (νΔ)⁴ ~ 1e-7 per crossing at worst; measured
    agreement 2.4e-12 relative. Asserted 1e-8."""
    sc = load_scene("dual_spin")
    n = gy.nutation(fmus["dual_spin"], sc, exudyn=False)
    print(n)
    assert n.closed == pytest.approx(np.sqrt(50.0 * 200.0 / (350.0 * 200.0)), rel=1e-15)
    assert n.fmu == pytest.approx(n.closed, rel=1e-8)


def test_the_unstable_wheel_grows_the_tilt_and_the_stable_one_does_not(fmus):
    """(c) h_w = 0 (the bare intermediate axis, k1 k2 = −5000): λ = sqrt(5000/70000) 1/s fitted
    from acosh(ω1/ε) = λ t, exact for the linearised spin (the nonlinear part (1e-4)² ~ 1e-8 at
    the fit's end); measured 6e-11 relative, asserted 1e-7. The scene's wheel (h_w = 100):
    |ω_⊥| stays at its start ε (transverse ratio 0.66 < 1), within 1e-6 of the bound 1."""
    sc = load_scene("dual_spin")
    sp = gy.spin_setup(sc)
    assert ds.stable(sp.I, sp.s, sp.w_s, sp.h_w) and not ds.stable(sp.I, sp.s, sp.w_s, 0.0)
    # the boundary of this body: k1 = h_w − 50, k2 = h_w + 100
    assert not ds.stable(sp.I, sp.s, sp.w_s, 49.0) and ds.stable(sp.I, sp.s, sp.w_s, 51.0)
    g = gy.growth(fmus["dual_spin"], sc)
    print(g)
    assert g.rate_fmu == pytest.approx(g.rate_closed, rel=1e-7)
    assert g.growth_unstable > 100.0
    assert g.growth_stable <= g.bound_stable * (1 + 1e-6)


@pytest.mark.parametrize("u", [0.0, 2.0])
def test_the_fmu_matches_the_jointed_exudyn_gyrostat(fmus, u):
    """(d) Exudyn: the wheel a second body on a revolute joint, trapezoidal rule at h = 2e-4 and
    1e-4 s, Richardson-extrapolated. The FMU (defaults: rk8, 1e-10 1/s) must agree with the
    extrapolation far better than Exudyn's own error |x(h) − x(2h)| at h: within 1 % of it plus
    a round-off floor of 1e-12 of the values (ω ~ 1 rad/s, Ω ~ 100 rad/s). Measured: u = 0
    |Δω| 5.9e-13 (estimate 1.5e-7), u = 2 N·m |Δω| 2.3e-10 (4.6e-7), |ΔΩ| 3.6e-9 (2.4e-4)."""
    a = gy.exudyn_agreement(fmus["dual_spin"], load_scene("dual_spin"), u)
    print(a)
    assert a.dw <= 0.01 * a.est_w + 1e-12
    assert a.dq <= 0.01 * a.est_q + 1e-12
    assert a.dOmega <= 0.01 * a.est_Omega + 1e-12 * 120.0


def test_rbfmu_check_reports_the_gyrostat_and_says_why_the_rigid_body_references_do_not_apply(fmus):
    """`rbfmu check --quick --scene dual_spin`: the registered rows, and the generic checks
    that model a rigid body are not applicable, with the reason (not silently wrong)."""
    assert "dual_spin" in registry.registered_scenes()
    rep = registry.scene_report("dual_spin", fmus["dual_spin"], quick=True)
    rows = {r.quantity: r for r in rep.rows}
    assert rows["nutation frequency, eps 1e-05 rad/s"].fmu == pytest.approx(0.3779644730092272, rel=1e-8)
    assert rows["max|L_world - L_world(0)| / |L|, u schedule"].fmu < 1e-13
    assert "rotors" in rep.not_applicable["closed-form trajectory"]
    assert "rbcheck.exudyn.rotors" in rep.not_applicable["FMU vs Exudyn trajectories"]
    assert "max|w - w_Exudyn|, u = 2 N m (Exudyn Richardson)" in registry.format_report(rep)
    # judged against rbcheck.checks.bounds: every row with a closed form or a reference, and passed
    assert not rep.failures() and sum(r.judged for r in rep.rows) == 10, registry.format_report(rep)


def test_model_exchange_integrates_the_rotor_state_like_co_simulation(fmus):
    """Model Exchange (fmpy's CVODE at rtol 1e-10) with a motor torque held at 1 N·m: the rotor
    state and its derivative der(Omega_wheel) go through the generic ME interface. CVODE's global
    error is a small multiple of rtol times each value (measured 8e-10 relative on L, |L| = 400
    N·m·s); asserted 1e-7 relative, as tests/fmi/test_fmi_breadth.py does for the rigid body."""
    from fmpy import simulate_fmu

    out = ["w_body[1]", "w_body[2]", "w_body[3]", "Omega_wheel", "L_world[1]", "L_world[2]", "L_world[3]"]
    common = {"stop_time": 5.0, "output_interval": 0.01, "output": out, "start_values": {"u_wheel": 1.0}}
    path = str(fmus["dual_spin"])
    cs = simulate_fmu(path, fmi_type="CoSimulation", **common)
    me = simulate_fmu(path, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10, **common)
    assert cs["Omega_wheel"][-1] - cs["Omega_wheel"][0] > 4.0  # the motor torque acted (∫u/J dt ~ 5 rad/s)
    L = np.linalg.norm([cs[f"L_world[{i}]"][0] for i in (1, 2, 3)])  # a vector's error is relative to its size
    for k in out:
        scale = L if k.startswith("L_world") else max(np.abs(cs[k]).max(), 1.0)
        assert np.abs(cs[k] - me[k]).max() <= 1e-7 * scale, k


# A heavy top (pivot, r_cm off the axes) and a free body in gravity with a full tensor, each
# carrying a tilted rotor: the feature combinations the dual-spin scene does not reach.
COMBOS = {
    "gyro_top": """
name = "gyro_top"
outputs = ["q", "w_body", "E_kin", "E_total", "L_world"]
[features]
gravity = true
[body]
principal_moments = [2.0, 2.0, 1.0]
mass = 3.0
[gravity]
r_cm = [0.1, -0.05, 0.3]
g = [0.0, 0.0, -9.81]
[rotors.a]
axis = [0.0, 0.6, 0.8]
J = 0.2
[initial]
w_body = [0.3, -1.0, 5.0]
euler_zxz = [0.2, 0.4, -0.3]
Omega_a = 30.0
""",
    "gyro_free": """
name = "gyro_free"
outputs = ["q", "w_body", "E_kin", "E_total", "L_world"]
[features]
translation = true
gravity = true
[body]
inertia = [[5.0, 0.3, -0.2], [0.3, 4.0, 0.1], [-0.2, 0.1, 3.0]]
mass = 3.0
[gravity]
g = [0.0, 0.0, -9.81]
[rotors.a]
axis = [0.0, 0.6, 0.8]
J = 0.2
[initial]
w_body = [0.3, -1.0, 5.0]
v_cm = [1.0, 2.0, 3.0]
Omega_a = 30.0
""",
}


@pytest.mark.parametrize("name", sorted(COMBOS))
def test_power_and_momentum_balances_hold_with_gravity_and_free_flight(tmp_path, name):
    """The time derivatives of the outputs along the generated vector field (model_output_rates,
    AD) at the start state, motor torque u = 1.5 N·m: dE_total/dt = u Ω (gravity is
    conservative, §8.2) and d L_world/dt = the external torque: its vertical component 0 about
    the top's pivot (gravity's moment is horizontal), all of it 0 for the free body (gravity at
    the centre of mass). Round-off of products of size ~50: 1e-12 absolute."""
    m = build_model(load_scene(write_scene(tmp_path, COMBOS[name], name)))
    f, vs = m.functions, m.variables
    p = np.array([v.start for v in vs if v.kind.name in ("PARAM_FIXED", "PARAM_TUNABLE")], dtype=float)
    d = np.asarray(f["model_derived"](p=p)["d"]).ravel()
    states = [v for v in vs if v.kind.name == "STATE"]
    x = np.array([v.start for v in states], dtype=float)
    u = np.array([1.5])
    z1 = np.asarray(f["model_output_rates"](x=x, u=u, p=p, d=d, u1=np.zeros(1), u2=np.zeros(1))["z1"]).ravel()
    rate = dict(zip([v.name for v in states] + [v.name for v in vs if v.kind.name == "OUTPUT"], z1))
    Omega = x[[v.name for v in states].index("Omega_a")]
    assert rate["E_total"] == pytest.approx(1.5 * Omega, rel=1e-13)
    assert abs(rate["L_world[3]"]) < 1e-12
    if name == "gyro_free":
        assert max(abs(rate[f"L_world[{i}]"]) for i in (1, 2)) < 1e-12
    else:
        assert max(abs(rate[f"L_world[{i}]"]) for i in (1, 2)) > 1.0  # the weight's moment turns L
