"""Torque inputs: body-frame and world-frame torques give the exact rigid-body response."""

from __future__ import annotations

import numpy as np

from fmu.drive.run import run_fmu
from modelsrc.quaternion import quat_from_euler_zxz
from modelsrc.scene import load_scene

EPS = np.finfo(float).eps


def test_constant_body_torque_from_rest(fmus):
    sc = load_scene("torque_driven")
    tau, I3 = 0.7, 3.0
    res = run_fmu(
        fmus["torque_driven"],
        sc,
        stop_time=2.0,
        step=0.01,
        input_fn=lambda t, y: {
            "tau_body[3]": tau,
            "tau_body[1]": 0.0,
            "tau_body[2]": 0.0,
            "tau_world[1]": 0.0,
            "tau_world[2]": 0.0,
            "tau_world[3]": 0.0,
        },
    )
    w = res.vector("w_body")
    # ω = τ t / I about a principal axis, exactly: RK4 integrates a constant ω̇ without
    # truncation error, only round-off accumulates (~ one ulp per step)
    assert np.max(np.abs(w[:, 2] - tau * res.time / I3)) <= res.n_steps * 10 * EPS * tau * 2.0 / I3
    assert np.all(w[:, :2] == 0.0)


def test_world_torque_is_applied_in_world_frame(fmus):
    sc = load_scene("torque_driven")
    tau, I2 = 0.4, 2.0
    q0 = quat_from_euler_zxz(np.pi / 2, 0.0, 0.0)  # body x -> world y, body y -> world −x
    start = {f"q[{k + 1}]": q0[k] for k in range(4)}
    zero = {f"tau_body[{k}]": 0.0 for k in (1, 2, 3)}
    res = run_fmu(
        fmus["torque_driven"],
        sc,
        stop_time=2.0,
        step=0.01,
        start_values=start,
        input_fn=lambda t, y: {**zero, "tau_world[1]": tau, "tau_world[2]": 0.0, "tau_world[3]": 0.0},
    )
    ww, wb = res.vector("w_world"), res.vector("w_body")
    expected = tau * res.time / I2  # torque about world x = about body −y, a principal axis, fixed in space
    tol = res.n_steps * 10 * EPS * expected[-1]
    assert np.max(np.abs(ww[:, 0] - expected)) <= tol
    assert np.max(np.abs(ww[:, 1:])) <= tol
    assert np.max(np.abs(wb[:, 1] + expected)) <= tol
    assert np.max(np.abs(wb[:, [0, 2]])) <= tol


def test_scene_input_tables_are_held_piecewise_constant(fmus):
    sc = load_scene("torque_driven")
    res = run_fmu(fmus["torque_driven"], sc)
    w = res.vector("w_body")
    first = res.time <= 2.0  # tau_body = (0, 0, 0.3) on [0, 2): ω3 = 0.3 t / 3 exactly
    assert np.max(np.abs(w[first, 2] - 0.1 * res.time[first])) <= 1e-13
    assert np.all(w[first, :2] == 0.0)
    assert 2.0 in res.time and 4.0 in res.time and 6.0 in res.time  # switching times are communication points
    assert np.abs(w[-1]).max() > 0.1  # later torques spin it about other axes
