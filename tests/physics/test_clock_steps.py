"""The orbit angle's sine and cosine in a fixed step: by angle addition from constants per step size.

A fixed rk4 or rk8 step of a scene with a clock (the orbit angle θ, θ̇ = n) evaluates sin θ and
cos θ once and turns them by the advances c h n of its stages, whose sines and cosines
model_step_constants_<method> computes once per step size (modelsrc/integrators.py, Clock,
step_constants). The steps under error control evaluate sin and cos at every stage. Checked here:
the two agree to round-off, the constants are read (wrong ones give another step), the fixed steps
hold one sine and one cosine, and the FMU recomputes the constants when the step size changes
between doSteps (its states then equal the generated step functions' own, bit for bit).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from fmu.linear.step_map import parameters
from modelsrc.integrators import advances
from modelsrc.methods import METHODS
from modelsrc.model import build_model
from modelsrc.scene import load_scene
from modelsrc.variables import Kind

from ..harness.fmi3_ctypes import OK, Fmi3Library, extract_fmu

CLOCK_SCENES = ("gravity_gradient_boom", "momentum_bias")


def _count(f: ca.Function, op: int) -> int:
    return sum(f.instruction_id(k) == op for k in range(f.n_instructions()))


@pytest.fixture(scope="module", params=CLOCK_SCENES)
def model(request):
    return build_model(load_scene(request.param))


@pytest.mark.parametrize("method", ["rk4", "rk8"])
def test_the_fixed_step_with_constants_is_the_step_with_sines_to_round_off(model, method):
    f = model.functions
    # a fast orbit (n = 0.5 rad/s, a step of 0.3 s turns θ by 0.15 rad) and a state away from
    # the scene's start, so that every stage's angle matters
    p = parameters(model, {"n_orbit": 0.5})
    d = np.asarray(f["model_derived"](p=p)["d"]).ravel()
    rng = np.random.default_rng(7)
    fixed, controlled = f[f"model_step_{method}_fixed"], f[f"model_step_{method}"]
    for _ in range(4):
        x = np.array([v.start for v in model.variables if v.kind == Kind.STATE]) + rng.uniform(-0.2, 0.2, model.nx)
        x[:4] /= np.linalg.norm(x[:4])
        x[-1] = rng.uniform(-7.0, 7.0)  # the orbit angle, the last state
        h = 0.3
        U = np.zeros(fixed.size1_in("U"))
        k1 = np.asarray(f["model_rhs"](x=x, u=np.zeros(model.nu), p=p, d=d)["xdot"]).ravel()
        e = np.asarray(f[f"model_step_constants_{method}"](p=p, h=h, d=d)["e"]).ravel()
        assert e.size == 2 * len(advances(method))
        a = fixed(x=x, U=U, p=p, h=h, d=d, k1=k1, e=e)
        b = controlled(x=x, U=U, p=p, h=h, d=d, k1=k1)
        for out in ("x_next", "k_next", "dx"):
            va, vb = np.asarray(a[out]).ravel(), np.asarray(b[out]).ravel()
            # the stage angles' sines differ by a few ulps (angle addition against sin of a
            # sum); through one step that is ~1e-16 of each state vector's size
            assert np.max(np.abs(va - vb)) <= 1e-14 * max(1.0, np.max(np.abs(vb))), out
        wrong = fixed(x=x, U=U, p=p, h=h, d=d, k1=k1, e=np.zeros_like(e))
        assert np.max(np.abs(np.asarray(wrong["x_next"] - b["x_next"]))) > 1e-4  # e is read


@pytest.mark.parametrize("method", ["rk4", "rk8"])
def test_a_fixed_step_evaluates_one_sine_and_one_cosine(model, method):
    f = model.functions
    fixed, controlled = f[f"model_step_{method}_fixed"], f[f"model_step_{method}"]
    assert (_count(fixed, ca.OP_SIN), _count(fixed, ca.OP_COS)) == (1, 1)
    # under error control: one pair per stage beyond the first and one for k_next (4 for rk4,
    # 12 for rk8: DOP853's 11 stages after k1, and k_next at θ + dx, not the last stage's θ + h n)
    n = _count(controlled, ca.OP_SIN)
    assert (n, _count(controlled, ca.OP_COS)) == ((4, 4) if method == "rk4" else (12, 12))


def test_no_constants_without_a_clock():
    f = build_model(load_scene("free_asymmetric")).functions
    assert not [k for k in f if k.startswith("model_step_constants")]
    assert f["model_step_rk4_fixed"].size1_in("e") == 0


@pytest.mark.parametrize("method", ["rk4", "rk8"])
def test_the_fmu_recomputes_the_constants_when_the_step_size_changes(fmus, tmp_path, method):
    """doSteps of 20, 15, 15 and 20 s (one internal step each: h_max above them, the scene's
    orbit rate and state), the last after h_max was set (a parameter change): the states after
    each equal the generated step functions' own, stepped with the constants of each step
    size, bit for bit. A stale e (the previous step size's advances, 5.8e-3 rad apart) turns
    the gravity-gradient torque by that angle: ~1e-8 rad/s in ω after one step."""
    scene = "gravity_gradient_boom"
    model = build_model(load_scene(scene))
    f = model.functions
    lib = Fmi3Library(extract_fmu(fmus[scene], tmp_path / "x"))
    vr = lib.info.vr
    values = {"h_max": 100.0, "tolerance": 0.0}
    inst = lib.instantiate()
    assert inst.set_int64([vr["method"]], [METHODS[method].value]) == OK, inst.log
    assert inst.set_float64([vr[n] for n in values], list(values.values())) == OK, inst.log
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK, inst.log
    states = [v.name for v in model.variables if v.kind == Kind.STATE]
    status, x = inst.get_float64([vr[n] for n in states])
    assert status == OK
    x = np.array(x)
    p = parameters(model, values)
    d = np.asarray(f["model_derived"](p=p)["d"]).ravel()
    step = f[f"model_step_{method}_fixed"]
    U = np.zeros(step.size1_in("U"))
    t = 0.0
    for H in (20.0, 15.0, 15.0, 20.0):
        if t == 50.0:  # a parameter set between doSteps: the constants are computed again
            assert inst.set_float64([vr["h_max"]], [200.0]) == OK, inst.log
        assert inst.do_step(t, H)[0] == OK, inst.log
        assert inst.get_float64([vr["internal_steps"]]) == (OK, [1.0])
        k1 = np.asarray(f["model_rhs"](x=x, u=np.zeros(model.nu), p=p, d=d)["xdot"]).ravel()
        e = np.asarray(f[f"model_step_constants_{method}"](p=p, h=H, d=d)["e"]).ravel()
        x = np.asarray(step(x=x, U=U, p=p, h=H, d=d, k1=k1, e=e)["x_next"]).ravel()
        t += H
        status, got = inst.get_float64([vr[n] for n in states])
        assert status == OK
        assert list(got) == list(x), (H, np.max(np.abs(np.array(got) - x)))
    # reset, another orbit rate, the same step size as the last doStep: the constants of the
    # old rate would turn the stage angles by 20 s x 3.4e-4 rad/s
    assert inst.reset() == OK, inst.log
    values["n_orbit"] = 1.5e-3
    assert inst.set_int64([vr["method"]], [METHODS[method].value]) == OK, inst.log
    assert inst.set_float64([vr[n] for n in values], list(values.values())) == OK, inst.log
    assert inst.enter_initialization_mode(0.0) == OK and inst.exit_initialization_mode() == OK, inst.log
    x = np.array(inst.get_float64([vr[n] for n in states])[1])
    p = parameters(model, values)
    d = np.asarray(f["model_derived"](p=p)["d"]).ravel()
    assert inst.do_step(0.0, 20.0)[0] == OK, inst.log
    assert inst.get_float64([vr["internal_steps"]]) == (OK, [1.0])
    k1 = np.asarray(f["model_rhs"](x=x, u=np.zeros(model.nu), p=p, d=d)["xdot"]).ravel()
    e = np.asarray(f[f"model_step_constants_{method}"](p=p, h=20.0, d=d)["e"]).ravel()
    x = np.asarray(step(x=x, U=U, p=p, h=20.0, d=d, k1=k1, e=e)["x_next"]).ravel()
    assert list(inst.get_float64([vr[n] for n in states])[1]) == list(x)
