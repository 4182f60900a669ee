"""A body held at its rate (prescribed_rate) is checked against its closed form; no reference simulates another system.

Before: `rbfmu check --scene` of a copy of skewed_bar failed with "no check applies" (the
closed-form trajectory called a held rate a torque without a closed form), the scipy
baselines integrated Euler's equations in place of the held rate, and
rbcheck.exudyn.motion.simulate ran a free body for a scene with a held rate or a central
field, which the report's batch part then drew as Exudyn lines (eccentric_orbit's stopped
at e = 3.5, "not reached"). Now: the uniform rotation q0 ⊗ exp(ω t / 2) is the closed form
(rbcheck.closed_forms.uniform_rotation), the baselines hold ω, and the Exudyn models refuse
what they do not model (rbcheck.exudyn.coverage).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fmu.build.build_fmu import build_fmu
from modelsrc.scene import list_scenes, load_scene
from rbcheck.baselines.motion import integrate
from rbcheck.baselines.rigid_body import comm_grid
from rbcheck.checks import registry
from rbcheck.closed_forms import uniform_rotation
from rbcheck.exudyn.coverage import covers
from rbcheck.exudyn.motion import simulate
from rbcheck.numerics.rotation_np import quat_to_matrix, rotation_angle_between


def test_the_uniform_rotation_solves_the_kinematics_at_a_held_rate():
    # q̇ = ½ q ⊗ (0, ω) at constant ω: the closed form's finite differences over 1e-5 s
    # (central, error O(h² |ω|³) ~ 1e-8 at |ω| = 10 rad/s) and |q| = 1
    w0, q0 = np.array([8.0, -5.0, 3.0]), np.array([0.9, 0.1, -0.3, 0.3])
    t, h = np.array([0.3, 1.7]), 1e-5
    _, q = uniform_rotation.solve(w0, q0, t)
    _, qp = uniform_rotation.solve(w0, q0, t + h)
    _, qm = uniform_rotation.solve(w0, q0, t - h)
    qn = q0 / np.linalg.norm(q0)
    assert np.allclose(uniform_rotation.solve(w0, q0, 0.0)[1][0], qn, rtol=0, atol=1e-16)
    for k in range(t.size):
        a, b, c, d = q[k]
        rate = 0.5 * np.array(
            [-b * w0[0] - c * w0[1] - d * w0[2], a * w0[0] + c * w0[2] - d * w0[1],
             a * w0[1] + d * w0[0] - b * w0[2], a * w0[2] + b * w0[1] - c * w0[0]]
        )  # fmt: skip
        assert np.max(np.abs((qp[k] - qm[k]) / (2 * h) - rate)) < 1e-7
        assert abs(np.linalg.norm(q[k]) - 1.0) < 1e-15


def test_the_scipy_baseline_holds_the_rate():
    # DOP853 at rtol 1e-12 over skewed_bar's 2 s (17 rad): the attitude within 1e-10 rad of
    # the closed form (before: Euler's equations turned ω, 2.9 rad off), ω exactly w0
    sc = load_scene("skewed_bar")
    grid = comm_grid(sc, 2.0, 0.2)
    tr = integrate(sc, grid, "DOP853", rtol=1e-12, atol=1e-14)
    w, q = uniform_rotation.solve(sc.w0, sc.q0, grid)
    assert np.all(tr.w_body == w)
    assert np.max(rotation_angle_between(quat_to_matrix(tr.q), quat_to_matrix(q))) < 1e-10


@pytest.mark.parametrize(
    ("scene", "feature"), [("skewed_bar", "prescribed_rate"), ("eccentric_orbit", "central_gravity")]
)
def test_exudyn_refuses_what_its_models_lack(scene, feature):
    sc = load_scene(scene)
    why = covers(sc)
    assert why is not None and feature in why
    with pytest.raises(ValueError, match=feature):
        simulate(sc, stop_time=0.1, step=0.1)


def test_exudyn_covers_the_rigid_bodies_it_models():
    covered = sorted(s for s in list_scenes() if covers(load_scene(s)) is None)
    assert covered == sorted(
        ["free_asymmetric", "heavy_top", "sleeping_top", "spacecraft_thruster", "symmetric_free", "thrown_racket",
         "top_on_shaker", "torque_driven", "two_frame_arm"]
    )  # fmt: skip


def test_a_user_scene_held_at_its_rate_is_judged_against_the_closed_form(tmp_path):
    # skewed_bar under another name: no check of its own, so only the generic ones; the
    # closed-form trajectory and the bearing torque R (ω × I ω) are judged and pass
    sc = dataclasses.replace(load_scene("skewed_bar"), name="held_bar")
    rep = registry.scene_report(sc, build_fmu(sc, tmp_path))  # host binary only
    text = registry.format_report(rep)
    assert not rep.failures(), text
    rows = {r.quantity: r for r in rep.rows}
    assert (
        rows["max_t attitude angle to closed form"].judged and rows["max_t attitude angle to closed form"].fmu < 1e-12
    )
    tau = rows["max_t |tau_bearing - R (w x I w)|"]
    assert tau.judged and tau.fmu < 1e-12, text  # |τ| = 3.6 N m: round-off
    assert np.isnan(tau.exudyn) and "no Exudyn run" in text and "prescribed_rate" in text
    assert sum(r.judged for r in rep.rows) == 6, text
