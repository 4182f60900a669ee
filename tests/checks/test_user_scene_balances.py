"""`rbfmu check --scene FILE` measures the balances any scene's features imply, at the scene's defaults.

Issue 24.7: a user scene with forces got only the generic checks (no balances), and the drift
rows ran rk4, gauss4 and splitting at fixed steps, never the scene's own method and settings.
The generic check "input balances" (rbcheck.checks.generic) applies rbcheck.checks.balances to
any scene whose inputs, forces, friction or moving pivot do work; the drift table starts with
a row at the scene's defaults.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fmu.build.build_fmu import build_fmu
from modelsrc.scene import ForcePoint, load_scene
from rbcheck.checks import registry
from rbcheck.checks.balances import balances, held_run

from ..harness.balances import assert_balances_fall_as_simpson
from ..harness.scenes import write_scene

# A free body in gravity pushed by a thruster off its centre of mass (the thrust turns with
# the body) and a world-frame force at another point, with a body torque: every balance of a
# free body has a term from each.
USER_SCENE = """
name = "user_thrusters"
outputs = ["q", "w_body", "w_world", "E_kin", "E_total", "L_world", "x_cm", "v_cm", "p"]
[features]
translation = true
gravity = true
torque_body = true
[body]
principal_moments = [2.0, 3.0, 4.0]
mass = 10.0
[gravity]
g = [0.0, 0.0, -9.81]
[forces.thruster]
point = [0.5, 0.2, 0.0]
frame = "body"
[forces.tether]
point = [0.0, -0.4, 0.3]
frame = "world"
[inputs]
f_thruster = [[0.0, 20.0, 0.0, 5.0], [0.3, 0.0, -10.0, 0.0], [0.6, 0.0, 0.0, 0.0]]
f_tether = [[0.0, 0.0, 3.0, 98.1], [0.5, 0.0, 0.0, 0.0]]
tau_body = [[0.0, 0.1, 0.0, -0.2], [0.4, 0.0, 0.0, 0.0]]
[initial]
w_body = [0.3, -0.2, 1.0]
v_cm = [1.0, 0.0, 2.0]
[experiment]
stop_time = 1.0
step = 0.01
methods = ["rk8"]  # the default; one method keeps the build short
"""


@pytest.fixture(scope="module")
def user_scene(tmp_path_factory):
    d = tmp_path_factory.mktemp("user_scene")
    path = write_scene(d, USER_SCENE, "user_thrusters")
    return path, build_fmu(load_scene(path), d)  # host binary only


def test_a_user_scene_with_force_points_gets_its_balances_at_its_defaults(user_scene):
    """On main the report had no balance rows for this scene. The residuals are the error of
    Simpson's rule per step, H⁵|f⁗|/2880 (the integrand is smooth on each step: the inputs jump
    only between steps), far above the FMU's own (tolerance 1e-10 1/s): halving H divides them
    by 2⁴ = 16 (measured 16.0, 16.0, 16.0 at H = 0.01 s: work 5.6e-7 J of 133 J done, momentum
    1.4e-8 N s, angular momentum 3.6e-8 N m s). A residual that did not fall so would be a
    modelling error, not quadrature (test_the_balances_see_a_wrong_lever_arm)."""
    path, fmu = user_scene
    sc = load_scene(path)
    rep = registry.scene_report(path, fmu, quick=True)
    assert "input balances" not in rep.not_applicable, rep.not_applicable
    assert f"at the scene's defaults ({sc.method}, tolerance 1e-10 1/s)" in rep.note
    rows = {r.quantity: r.fmu for r in rep.rows}
    assert abs(rows["work done by the inputs, int P dt"]) > 100.0  # the inputs do work: a real test
    assert_balances_fall_as_simpson(rows, balances(sc, held_run(fmu, sc, sc.stop_time, step=sc.step / 2)))


def test_the_balances_see_a_wrong_lever_arm(user_scene):
    """The same run booked with the thruster 1 cm further out along body x (in the balance, not
    in the FMU) misses the angular-momentum balance by the torque error's impulse,
    |Δr × F| ~ 0.01 m x 20 N x 0.3 s = 0.06 N m s: the check can see such an error."""
    path, fmu = user_scene
    sc = load_scene(path)
    run = held_run(fmu, sc, 1.0)
    fp = sc.force_points["thruster"]
    wrong = dataclasses.replace(
        sc, force_points={**sc.force_points, "thruster": ForcePoint(fp.point + [0.01, 0, 0], fp.frame)}
    )
    right, off = balances(sc, run), balances(wrong, run)
    assert off.angular_momentum > 1e-2 and off.angular_momentum > 1e5 * right.angular_momentum, (off, right)


def test_a_moving_pivot_balances_its_momentum_with_the_pivot_force(fmus):
    """top_on_shaker at its defaults (rk8, 1e-10): p(t) − p(0) = ∫ (f_pivot + M g) dt, to
    Simpson's error per step (halving H divides it by ~16; measured 3.2e-11 N s over 0.1 s at
    H = 1 ms), and f_pivot = M (a_cm − g) at every sample (the FMU's outputs satisfy it to the
    last bit: a consistency row, the momentum balance is the physical test)."""
    sc = load_scene("top_on_shaker")
    b = balances(sc, held_run(fmus["top_on_shaker"], sc, 0.1))
    half = balances(sc, held_run(fmus["top_on_shaker"], sc, 0.1, step=sc.step / 2))
    assert b.pivot_force <= 1e-12 * float(sc.mass) * 9.81, b
    assert 10.0 < b.momentum / half.momentum < 22.0, (b, half)
    assert np.isnan(b.angular_momentum)
