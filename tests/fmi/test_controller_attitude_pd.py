"""The attitude_pd controller FMU (modelsrc/controllers/): its law, limits, sampling and closed loop, FMI 3.0 and 2.0.

Built once per module (host binary only). The law is compared with rbcheck's independent
PDSlew (numpy), the closed loop (plant reaction_wheel_slew + controller, driven by plain fmpy
calls) with the exact sampled-data recursion rbcheck.closed_forms.slew.eigenaxis_reference.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fmu.build.controller_build import build_controller
from modelsrc.controllers.controller_file import load_controller
from modelsrc.errors import ModelInputError
from modelsrc.scene import load_scene
from rbcheck.closed_forms.slew import SLEW_GAINS, eigenaxis_reference, slew_law

from ..harness.scenes import shared_fmu
from ..harness.slave import Slave

WHEELS = ("x", "y", "z")


@pytest.fixture(scope="module")
def ctrl_fmus(tmp_path_factory):
    out = tmp_path_factory.mktemp("controllers")
    return {v: build_controller("attitude_pd", out, fmi_version=v) for v in (3, 2)}


@pytest.fixture(scope="module")
def law():
    return slew_law(load_scene("reaction_wheel_slew"), *SLEW_GAINS)


def inputs(q, w, Om=(0.0, 0.0, 0.0)) -> dict[str, float]:
    d = {f"q[{i + 1}]": float(q[i]) for i in range(4)}
    d.update({f"w_body[{i + 1}]": float(w[i]) for i in range(3)})
    d.update({f"Omega_{n}": float(o) for n, o in zip(WHEELS, Om)})
    return d


U = [f"u_{n}" for n in WHEELS]
NO_LIMITS = {**{f"u_max_{n}": 1e6 for n in WHEELS}, **{f"Omega_max_{n}": 1e6 for n in WHEELS}}


@pytest.mark.parametrize("version", [3, 2])
def test_the_outputs_are_rbchecks_pd_law_at_the_current_inputs(ctrl_fmus, law, version):
    """500 random (q, ω) (q of any norm near 1, either sign of q_e0) at t = 0, a sample point:
    the outputs are PDSlew's u (numpy, the same operations), measured max difference 0; asserted
    ≤ 1e-14 N·m (round-off of |u| ~ 10)."""
    c = Slave(ctrl_fmus[version], version, NO_LIMITS)
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(500):
        q = rng.normal(size=4)
        q *= (1 + 1e-3 * rng.normal()) / np.linalg.norm(q)
        w = rng.normal(size=3)
        c.set(inputs(q, w))
        ref = law(0.0, inputs(q, w))
        worst = max(worst, float(np.max(np.abs(c.get(U) - np.array([ref[u] for u in U])))))
    c.close()
    print(f"FMI {version}: max |u - PDSlew| = {worst:.3g} N m")
    assert worst <= 1e-14


def reference_limited(law, q, w, Om, u_max, om_max) -> np.ndarray:
    """The documented limits in numpy: clip to ±u_max, then no torque that speeds a wheel at |Ω| ≥ Ω_max further."""
    ref = law(0.0, inputs(q, w))
    u = np.clip(np.array([ref[k] for k in U]), -u_max, u_max)
    u[(np.asarray(Om) >= om_max) & (u > 0)] = 0.0
    u[(np.asarray(Om) <= -om_max) & (u < 0)] = 0.0
    return u


@pytest.mark.parametrize("version", [3, 2])
def test_saturation_and_the_wheel_speed_limit_cut_as_documented(ctrl_fmus, law, version):
    """u_max = 0.8 N·m, Ω_max = 50 rad/s, random inputs with wheel rates in ±80 rad/s: the outputs are
    the clipped law, zero where the wheel is at its limit and the torque would speed it up (numpy
    rule of the module docstring of modelsrc/controllers/attitude_pd.py); both limits are hit."""
    c = Slave(
        ctrl_fmus[version], version, {**{f"u_max_{n}": 0.8 for n in WHEELS}, **{f"Omega_max_{n}": 50.0 for n in WHEELS}}
    )
    rng = np.random.default_rng(3)
    worst, clipped, cut = 0.0, 0, 0
    for _ in range(400):
        q, w, Om = rng.normal(size=4), 0.3 * rng.normal(size=3), rng.uniform(-80, 80, size=3)
        q /= np.linalg.norm(q)
        c.set(inputs(q, w, Om))
        y = c.get(U)
        ref = reference_limited(law, q, w, Om, 0.8, 50.0)
        raw = law(0.0, inputs(q, w))
        clipped += int(np.sum(np.abs([raw[k] for k in U]) > 0.8))
        cut += int(np.sum((ref == 0.0) & (np.abs(Om) >= 50.0)))
        worst = max(worst, float(np.max(np.abs(y - ref))))
    c.close()
    assert clipped > 50 and cut > 50
    assert worst <= 1e-14


def test_the_integral_term_sums_the_error_at_each_sample(ctrl_fmus, law):
    """k_i = 0.3, q fixed at 30° about (1, 2, 2)/3, ω = 0, Ts = 0.1 s: z_k = k Ts q_e,vec, and u at
    sample k is PDSlew's minus G⁻¹ I_r k_i z_k (G = 1 here); the discrete state e_int reads z_k."""
    c = Slave(ctrl_fmus[3], 3, {**NO_LIMITS, "k_i": 0.3})
    n = np.array([1.0, 2.0, 2.0]) / 3
    q = np.array([math.cos(math.pi / 12), *(math.sin(math.pi / 12) * n)])
    c.set(inputs(q, np.zeros(3)))
    base = np.array([law(0.0, inputs(q, np.zeros(3)))[k] for k in U])
    for k in range(4):
        z = k * 0.1 * q[1:]
        np.testing.assert_allclose(c.get([f"e_int[{i}]" for i in (1, 2, 3)]), z, rtol=0, atol=1e-15)
        np.testing.assert_allclose(c.get(U), base + law.I_r @ (0.3 * z), rtol=0, atol=1e-14)
        c.step(0.1 * k, 0.1)
    c.close()


E_INT = [f"e_int[{i}]" for i in (1, 2, 3)]


def _integral_over_samples(c, q, w, n: int = 4) -> list[np.ndarray]:
    """e_int at the first n sample points (Ts = 0.1 s) with the inputs q, w held."""
    c.set(inputs(q, w))
    out = []
    for k in range(n):
        out.append(c.get(E_INT))
        c.step(0.1 * k, 0.1)
    return out


@pytest.mark.parametrize("anti_windup", [1.0, 0.0])
def test_the_integral_stops_growing_while_a_torque_limit_saturates(ctrl_fmus, law, anti_windup):
    """k_i = 0.3, q fixed at 30° about (1, 2, 2)/3, ω = 0, torque limit 0.01 N·m (PDSlew's |u| ~ 1.2
    N·m: every wheel saturated, the increment pushing each further): with anti_windup = 1 (the
    default; conditional integration) e_int stays 0 over 4 samples; with 0 it grows as k Ts q_e,vec."""
    limited = {**NO_LIMITS, "k_i": 0.3, "anti_windup": anti_windup, **{f"u_max_{n}": 0.01 for n in WHEELS}}
    c = Slave(ctrl_fmus[3], 3, limited)
    n = np.array([1.0, 2.0, 2.0]) / 3
    q = np.array([math.cos(math.pi / 12), *(math.sin(math.pi / 12) * n)])
    base = np.array([law(0.0, inputs(q, np.zeros(3)))[k] for k in U])
    assert np.all(np.abs(base) > 0.01)  # the unlimited command is past every wheel's limit
    c.set(inputs(q, np.zeros(3)))
    np.testing.assert_array_equal(c.get(U), 0.01 * np.sign(base))
    for k, z in enumerate(_integral_over_samples(c, q, np.zeros(3))):
        np.testing.assert_allclose(z, k * 0.1 * q[1:] * (1.0 - anti_windup), rtol=0, atol=1e-15)
    c.close()


def test_the_integral_goes_on_when_its_increment_pulls_the_command_back_from_the_limit(ctrl_fmus, law):
    """Conditional integration holds only an increment that pushes a limited command further: q at
    30° about n = (1, 2, 2)/3 and ω = −2 n rad/s, so that the rate term saturates every wheel the
    other way (u opposite to the k_p term's); the increment then pulls the command back from the
    limit and e_int grows as k Ts q_e,vec."""
    c = Slave(ctrl_fmus[3], 3, {**NO_LIMITS, "k_i": 0.3, **{f"u_max_{n}": 0.01 for n in WHEELS}})
    n = np.array([1.0, 2.0, 2.0]) / 3
    q = np.array([math.cos(math.pi / 12), *(math.sin(math.pi / 12) * n)])
    w = -2.0 * n
    base = np.array([law(0.0, inputs(q, w))[k] for k in U])
    p_only = np.array([law(0.0, inputs(q, np.zeros(3)))[k] for k in U])
    assert np.all(np.abs(base) > 0.01) and np.all(np.sign(base) == -np.sign(p_only))
    for k, z in enumerate(_integral_over_samples(c, q, w)):
        np.testing.assert_allclose(z, k * 0.1 * q[1:], rtol=0, atol=1e-15)
    c.close()


@pytest.mark.parametrize("version", [3, 2])
def test_outputs_are_held_between_samples_and_a_step_over_a_sample_point_is_refused(ctrl_fmus, law, version):
    """Ts = 0.1 s, H = 0.05 s: at t = 0.05 (between samples) new inputs leave the outputs at the
    value latched at t = 0; at t = 0.1 they are the law at the inputs then. A doStep of 0.15 s from
    t = 0.1 would contain the sample point 0.2: refused, the FMU's time unchanged."""
    c = Slave(ctrl_fmus[version], version, NO_LIMITS)
    qa, qb = np.array([0.9, 0.1, 0.2, 0.3]), np.array([0.8, -0.3, 0.1, 0.4])
    c.set(inputs(qa, [0.1, 0, 0]))
    ua = c.get(U)
    c.step(0.0, 0.05)
    c.set(inputs(qb, [0, 0.2, 0]))
    assert np.array_equal(c.get(U), ua)
    c.step(0.05, 0.05)
    ref = law(0.0, inputs(qb, [0, 0.2, 0]))
    assert np.array_equal(c.get(U), [ref[k] for k in U])
    with pytest.raises(Exception, match="status 3"):
        c.step(0.1, 0.15)
    if version == 3:
        assert any("sample point t=0.2" in m and "Ts=0.1" in m and "H=0.1499" in m for m in c.log), c.log
    c.step(0.1, 0.1)  # still at t = 0.1
    c.close()


def closed_loop(plant_fmu, ctrl_fmu, version: int, H: float, T: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Plant and controller stepped together by plain fmpy calls: at each t_k the controller's
    inputs are set from the plant's outputs, its u read and set on the plant, then both step H.
    Returns (t, q, w_body) at the communication points."""
    plant = Slave(plant_fmu, 3)
    ctrl = Slave(ctrl_fmu, version)
    names = [f"q[{i}]" for i in range(1, 5)] + [f"w_body[{i}]" for i in range(1, 4)] + [f"Omega_{n}" for n in WHEELS]
    n = round(T / H)
    ts, rows = [], []
    for k in range(n + 1):
        t = k * H
        y = plant.get(names)
        ts.append(t)
        rows.append(y)
        if k == n:
            break
        ctrl.set(dict(zip(names, y)))
        plant.set(dict(zip(U, ctrl.get(U))))
        plant.step(t, H)
        ctrl.step(t, H)
    plant.close()
    ctrl.close()
    Y = np.array(rows)
    return np.array(ts), Y[:, :4], Y[:, 4:7]


@pytest.mark.parametrize(("version", "H"), [(3, 0.1), (2, 0.1), (3, 0.05)])
def test_the_closed_loop_meets_the_exact_sampled_data_slew(build_dir, ctrl_fmus, version, H):
    """reaction_wheel_slew + attitude_pd (Ts = 0.1 s) over 40 s, communication step H = Ts, and
    H = Ts/2 (the controller holds u over two plant steps): at the sample points the attitude
    angle about the eigenaxis and the rate meet eigenaxis_reference (exact for u held over Ts);
    the plant's rk8 (error-controlled) meets it to round-off: measured 4e-16 rad, 1.1e-16 rad/s
    (H = Ts), 1e-15 rad (H = Ts/2); asserted 1e-12 (round-off of 40 s of steps; the required
    figure of the closed loop is 1e-8 rad and 1e-9 rad/s)."""
    sc = load_scene("reaction_wheel_slew")
    t, q, w = closed_loop(shared_fmu(build_dir, "reaction_wheel_slew"), ctrl_fmus[version], version, H, 40.0)
    m = round(0.1 / H)
    t, q, w = t[::m], q[::m], w[::m]
    v0 = np.asarray(sc.q0[1:], dtype=float)
    axis = v0 / np.linalg.norm(v0)
    phi0 = 2.0 * math.atan2(float(np.linalg.norm(v0)), float(sc.q0[0]))
    phi_ref, dphi_ref = eigenaxis_reference(phi0, *SLEW_GAINS, 0.1, len(t) - 1)
    phi = 2.0 * np.arctan2(q[:, 1:] @ axis, q[:, 0])
    dphi = float(np.max(np.abs(phi - phi_ref)))
    dw = float(np.max(np.abs(w - dphi_ref[:, None] * axis)))
    print(f"FMI {version}, H = {H}: max |phi - ref| = {dphi:.3g} rad, max |w - ref| = {dw:.3g} rad/s")
    assert abs(phi[0]) > 1.5 and abs(phi[-1]) < 1e-5  # it did slew
    assert dphi <= 1e-12 and dw <= 1e-12


def write(tmp_path, text: str, name: str = "c.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


BASE = 'law = "attitude_pd"\nplant = "reaction_wheel_slew"\nsample_period = 0.1\n'


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (BASE + "[gains]\nk_p = -0.5\n", r"field 'gains.k_p': must be >= 0, got -0.5"),
        (BASE + "[gains]\nk_d = nan\n", r"field 'gains.k_d': must be finite, got nan"),
        (BASE + "[gains]\nk_i = inf\n", r"field 'gains.k_i': must be finite, got inf"),
        (BASE.replace("0.1", "0.0"), r"field 'sample_period': must be > 0, got 0.0"),
        (BASE.replace("0.1", "-1"), r"field 'sample_period': must be > 0, got -1.0"),
        (BASE.replace("reaction_wheel_slew", "no_such_plant"), r"field 'plant': unknown scene 'no_such_plant'"),
        (BASE.replace("reaction_wheel_slew", "quadrotor"), r"scene 'quadrotor' has 0 torque-mode wheels; .*exactly 3"),
        (BASE + "[limits]\ntorque = 0\n", r"field 'limits.torque': must be in"),
        (BASE + "[limits]\nanti_windup = 0.5\n", r"field 'limits.anti_windup': must be 1 .* or 0 .*, got 0.5"),
        (BASE + "[target]\nq = [1.0, 0.1, 0.0, 0.0]\n", r"field 'target.q': must be a unit quaternion"),
        (BASE.replace("attitude_pd", "pid"), r"field 'law': 'pid' is not a law"),
        (BASE + "gain = 1\n", r"field 'gain': unknown key"),
    ],
)
def test_a_bad_controller_file_is_refused_naming_the_value(tmp_path, text, message):
    with pytest.raises(ModelInputError, match=message):
        load_controller(write(tmp_path, text))


def test_a_bad_value_set_on_the_fmu_is_refused_and_undone(ctrl_fmus):
    """In Step Mode a negative gain fails the parameter check and is undone; Ts (fixed) cannot be set."""
    c = Slave(ctrl_fmus[3], 3)
    with pytest.raises(Exception, match="status 3"):
        c.set({"k_p": -1.0})
    assert c.get(["k_p"])[0] == 0.5
    assert any("k_p >= 0" in m for m in c.log), c.log
    with pytest.raises(Exception, match="status 3"):
        c.set({"Ts": 0.2})
    assert any("'Ts' is a fixed parameter" in m for m in c.log), c.log
    with pytest.raises(Exception, match="status 3"):
        c.set({"anti_windup": 2.0})
    assert c.get(["anti_windup"])[0] == 1.0 and any("anti_windup = 0 or 1" in m for m in c.log), c.log
    c.close()
