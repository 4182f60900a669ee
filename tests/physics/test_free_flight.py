"""Free flight (feature translation) and forces at points: the FMU against closed forms and exact balances.

The closed forms of rbcheck.closed_forms.free_flight and rbcheck.closed_forms.free_asymmetric, docs/theory.md §7.
Every method integrates a constant acceleration exactly (Runge-Kutta and Gauss methods
of order >= 2 are exact on quadratic polynomials; the splittings' kick-drift-kick is the
exact flow), so the centre of mass is compared at round-off: a tolerance of N eps times
the position scale, N the number of internal steps (a worst-case accumulation).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from fmu.build.build_fmu import build_fmu, ensure_fmu
from fmu.drive.instance import FmuInstance
from fmu.drive.run import run_fmu
from modelsrc.methods import METHODS
from modelsrc.scene import load_scene
from rbcheck.checks.balances import balances, held_run
from rbcheck.closed_forms import free_asymmetric
from rbcheck.closed_forms.free_flight import impulse, parabola
from rbcheck.numerics.rotation_np import quat_to_matrix, rotation_angle_between

from ..harness.scenes import write_scene

EPS = np.finfo(float).eps
# free_asymmetric's closed form of the racket's spin differs from Exudyn RK67 (error
# estimate 1.4e-12) by 3.3e-10 rad/s and 2.8e-11 rad (rbfmu check): its own error
CLOSED_FORM_FLOOR = 1e-9


def _rot_errors(r, sc):
    w, q = free_asymmetric.solve(np.diag(sc.inertia), sc.w0, sc.q0, r.time)
    dw = float(np.max(np.abs(r.vector("w_body") - w)))
    da = float(np.max(rotation_angle_between(quat_to_matrix(r.vector("q")), quat_to_matrix(q))))
    return dw, da


@pytest.mark.parametrize("method", list(METHODS))
def test_thrown_racket_flies_the_exact_parabola(fmus, method):
    sc = load_scene("thrown_racket")
    r = run_fmu(fmus["thrown_racket"], sc, start_values={"method": METHODS[method].value})
    x, v = parabola(sc.x0, sc.v0, sc.g, r.time)
    # internal steps: at most those of fixed steps of the scene's fixed step and the rotation limits' refinement
    n = math.ceil(sc.stop_time / sc.fixed_step) * 20
    scale = float(np.max(np.abs(x))) + float(np.max(np.abs(v))) * sc.stop_time
    assert np.max(np.abs(r.vector("x_cm") - x)) < n * EPS * scale
    assert np.max(np.abs(r.vector("v_cm") - v)) < n * EPS * scale / sc.stop_time
    assert np.max(np.abs(r.vector("a_cm") - sc.g)) < 10 * EPS * 9.81  # M g / M, no other force
    # the momentum and energy of the flight: p = M v, E_total = ½ M v² + ½ ωᵀIω − M g·x
    assert np.max(np.abs(r.vector("p") - sc.mass * r.vector("v_cm"))) < 10 * EPS * sc.mass * 8.0
    w = r.vector("w_body")
    E = 0.5 * sc.mass * np.sum(v * v, axis=1) + 0.5 * np.einsum("ni,ij,nj->n", w, sc.inertia, w)
    assert np.max(np.abs(r.values["E_kin"] - E)) < 1e-9 * float(np.max(E))  # ω to the method's error


@pytest.mark.parametrize("H", [0.35, 0.7])
def test_exact_free_is_exact_at_any_step_in_uniform_gravity(fmus, H):
    sc = load_scene("thrown_racket")
    r = run_fmu(fmus["thrown_racket"], sc, step=H, start_values={"method": METHODS["exact_free"].value, "h_max": H})
    assert len(r.time) == round(sc.stop_time / H) + 1  # one internal step per communication step
    x, v = parabola(sc.x0, sc.v0, sc.g, r.time)
    assert np.max(np.abs(r.vector("x_cm") - x)) < 100 * EPS * float(np.max(np.abs(x)))
    assert np.max(np.abs(r.vector("v_cm") - v)) < 100 * EPS * float(np.max(np.abs(v)))
    dw, da = _rot_errors(r, sc)
    print(f"\nexact_free at H = {H} s: |dx| {np.max(np.abs(r.vector('x_cm') - x)):.1e} m, |dw| {dw:.1e}, {da:.1e} rad")
    assert dw < CLOSED_FORM_FLOOR * 12.0 and da < CLOSED_FORM_FLOOR


def test_sensor_point_moves_with_the_centre_of_mass(fmus):
    # v = v_cm + ω × r and a = a_cm + ω̇ × r + ω × (ω × r) (MIT 2.003J handout §4–5)
    sc = load_scene("spacecraft_thruster")
    r = run_fmu(fmus["spacecraft_thruster"], sc, stop_time=6.0)
    R = quat_to_matrix(r.vector("q"))
    rw = R @ np.asarray(sc.sensor_point)
    w = r.vector("w_world")
    assert np.max(np.abs(r.vector("sensor_r") - (r.vector("x_cm") + rw))) < 1e-14
    assert np.max(np.abs(r.vector("sensor_v") - (r.vector("v_cm") + np.cross(w, rw)))) < 1e-15
    # ω̇ from the FMU's Model Exchange derivatives at the end (t = 6 s, thruster off: torque-free)
    with FmuInstance(fmus["spacecraft_thruster"]) as inst:
        inst.initialize(0.0, 1.0)
        a0 = inst.get([f"a_cm[{k}]" for k in (1, 2, 3)])
        wdot0 = inst.get([f"der(w_body[{k}])" for k in (1, 2, 3)])
    # at t = 0 from rest: a_cm = F/M and I ω̇ = r × F (the thruster pushes and spins at once)
    F, rp = np.array([50.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.3])
    assert np.allclose(a0, F / sc.mass, rtol=0, atol=1e-16)
    assert np.allclose(wdot0, np.cross(rp, F) / np.diag(sc.inertia), rtol=1e-15, atol=0)


IMPULSE_SCENE = """
name = "impulse_body"
description = "free body pushed by a random piecewise-constant world force at an off-centre point, in gravity"
outputs = ["q", "w_body", "E_kin", "E_total", "L_world", "p", "a_cm"]
[features]
translation = true
gravity = true
force_world = true
[body]
principal_moments = [1.0, 2.0, 3.0]
mass = 2.0
[gravity]
g = [0.0, 0.0, -9.81]
[forces.arm]
point = [0.3, -0.2, 0.1]
frame = "world"
[initial]
w_body = [0.3, -0.2, 0.5]
v_cm = [1.0, 2.0, 3.0]
[experiment]
stop_time = 2.0
step = 0.05
h_max = 0.01
methods = ["rk4", "gauss4", "splitting", "exact_free"]
"""


@pytest.fixture(scope="module")
def impulse_fmu(tmp_path_factory):
    d = tmp_path_factory.mktemp("impulse")
    path = write_scene(d, IMPULSE_SCENE, "impulse_body")
    return path, ensure_fmu(load_scene(path), d)


@pytest.mark.slow  # builds its own FMU (~6 s)
@pytest.mark.parametrize("method", ["rk4", "gauss4", "splitting", "exact_free"])
def test_momentum_is_the_impulse_of_any_force_history(impulse_fmu, method):
    path, fmu = impulse_fmu
    sc = load_scene(path)
    rng = np.random.default_rng(7)
    F_com = rng.normal(0.0, 5.0, size=(40, 3))  # f_world, held over each step
    F_arm = rng.normal(0.0, 5.0, size=(40, 3))  # the off-centre world force (it also turns the body)

    def inputs(t, _out):
        k = min(round(t / sc.step), 39)
        return {f"f_world[{j + 1}]": F_com[k, j] for j in range(3)} | {f"f_arm[{j + 1}]": F_arm[k, j] for j in range(3)}

    r = run_fmu(fmu, sc, input_fn=inputs, start_values={"method": METHODS[method].value})
    grid = r.time
    J = impulse(grid, (F_com + F_arm)[: len(grid) - 1] + sc.mass * np.asarray(sc.g))
    p0 = sc.mass * np.asarray(sc.v0)
    dp = np.max(np.abs(r.vector("p") - p0 - J))
    print(f"\n{method}: max |p - p0 - int F dt| = {dp:.1e} N s over {len(grid) - 1} steps")
    # exact for every method (the force is held constant in the world frame): round-off of
    # N = 200 internal steps of |p| ~ 20 N s
    assert dp < 200 * EPS * 40.0


def test_work_and_momentum_balances_of_the_thruster(fmus):
    # docs/theory.md §7: E_total(t) − E_total(0) = ∫ F·(v_cm + ω × r) dt, p(t) − p(0) = ∫ F dt,
    # L(t) − L(0) = ∫ r × F dt. Simpson per step of H = 1e-2 s errs by H⁵|P⁗|/2880, over
    # 2000 steps ≤ 3e-11 J (|P⁗| ≤ |F| |v| ν⁴ + 4 |F| |a| ν³ ≤ 4e-3 W/s⁴ with ν = |ω| ≤ 0.25
    # rad/s, |v| ≤ 0.6 m/s, |a| = 0.1 m/s²); RK4's own error in E at h|ω| ≤ 3e-3 is below
    # 1e-13 of E (the drift tables of rbfmu check): 1e-10 E keeps a margin of 3
    sc = load_scene("spacecraft_thruster")
    b = balances(sc, held_run(fmus["spacecraft_thruster"], sc, sc.stop_time, step=0.01))
    print(
        f"\nthruster: work {b.work:.1e} J of {b.work_done:.4g} J, momentum {b.momentum:.1e}, L {b.angular_momentum:.1e}"
    )
    assert b.work_done > 90.0  # the burns did work (E_kin(T) = 96.6 J)
    assert b.work < 1e-10 * b.E_scale
    assert b.momentum < 1e-10 * sc.mass * 1.0  # |v| < 1 m/s
    assert b.angular_momentum < 1e-10 * 100.0  # |L| ~ 100 N m s


@pytest.mark.slow
def test_fmi2_and_fmi3_archives_validate_and_run_model_exchange(fmus, tmp_path):
    """validate_fmu is clean for FMI 2.0 (FMI 3.0: tests/build/test_fmu_structure.py, every
    scene); fmpy's CVODE on the Model Exchange interface of both flies the parabola
    (CVODE's error: a small multiple of rtol·|x|)."""
    sc = load_scene("thrown_racket")
    for name in ("thrown_racket", "spacecraft_thruster", "top_on_shaker"):
        # rk4 only: the variables and the structure do not depend on the methods, and the
        # exact free flow's large generated C would triple the build time
        rk4_only = dataclasses.replace(load_scene(name), methods=("rk4",), method="rk4")
        fmu = build_fmu(rk4_only, tmp_path, fmi_version=2)
        assert validate_fmu(str(fmu)) == [], name
    for version in (2, 3):
        fmu = fmus["thrown_racket"] if version == 3 else tmp_path / "thrown_racket_fmi2.fmu"
        out = [f"x_cm[{k}]" for k in (1, 2, 3)] + [f"w_body[{k}]" for k in (1, 2, 3)]
        me = simulate_fmu(
            str(fmu), fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-10, stop_time=1.4, output=out
        )
        x, _ = parabola(sc.x0, sc.v0, sc.g, me["time"])
        dx = max(float(np.max(np.abs(me[f"x_cm[{k}]"] - x[:, k - 1]))) for k in (1, 2, 3))
        print(f"\nFMI {version} ME under CVODE: max |x_cm - parabola| = {dx:.1e} m")
        assert dx < 1e-7


@pytest.mark.slow  # builds its own FMU
def test_a_force_point_declared_at_the_centre_of_mass_stays_there(tmp_path):
    path = write_scene(
        tmp_path,
        """
name = "central_push"
[features]
translation = true
[body]
principal_moments = [1.0, 2.0, 3.0]
mass = 1.0
[forces.jet]
point = [0.0, 0.0, 0.0]
frame = "world"
[initial]
w_body = [0.0, 1.0, 0.0]
[experiment]
stop_time = 0.1
methods = ["rk4"]
""",
        "central_push",
    )
    sc = load_scene(path)
    assert sc.torque_free and sc.exact_flow  # a world force through the centre of mass: no torque
    fmu = ensure_fmu(sc, tmp_path)
    run_fmu(fmu, sc)  # at the centre of mass: runs
    from fmu.drive.instance import FmuError

    with pytest.raises(FmuError, match=r"force point 'jet' was declared at the centre of mass.*r_jet must stay 0"):
        run_fmu(fmu, sc, start_values={"r_jet[2]": 0.1})
