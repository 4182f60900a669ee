"""MIT 2.003J examples, FMU vs closed form vs Exudyn: the skewed bar's bearing torque and the two-frame arm.

The arm: velocity and acceleration of a body point."""

from __future__ import annotations

import numpy as np
import pytest

from fmu.drive.run import run_fmu
from modelsrc.quaternion import quat_from_euler_zxz
from modelsrc.scene import load_scene
from rbcheck.closed_forms.frame_kinematics import arm_wrist
from rbcheck.closed_forms.skewed_bar import bearing_torque
from rbcheck.exudyn import models as exudyn_models
from rbcheck.exudyn.skewed_bar import exudyn_revolute

I_A, I_T, THETA_DOT = 5.0e-5, 0.083358333333333333, 10.0


def run_bar(fmu, phi: float, T: float = 1.0):
    """The FMU's skewed bar at angle phi: orientation Rz(phi), ω = θ̇ e_x (world)."""
    q0 = quat_from_euler_zxz(phi, 0.0, 0.0)
    w_body = THETA_DOT * np.array([np.cos(phi), -np.sin(phi), 0.0])
    start = {**{f"q[{k + 1}]": q0[k] for k in range(4)}, **{f"w_body[{k + 1}]": w_body[k] for k in range(3)}}
    return run_fmu(fmu, load_scene("skewed_bar"), stop_time=T, start_values=start)


@pytest.mark.parametrize("phi", [np.pi / 6, 1.0, 0.0, np.pi / 2])
def test_bearing_torque_matches_formula_and_exudyn(fmus, phi):
    res = run_bar(fmus["skewed_bar"], phi)
    tau = res.vector("tau_bearing")
    ref = bearing_torque(res.time, I_A, I_T, phi, THETA_DOT)
    scale = (I_T - I_A) * THETA_DOT**2 / 2  # largest |τ| over φ
    # RK4 with h·θ̇ = 0.01: phase error ~ 1000 steps·(0.01)⁵/120 ≈ 1e-10 rad -> 1e-9 of scale
    err_fmu = np.max(np.abs(tau - ref))
    assert err_fmu < 1e-9 * scale
    ex = exudyn_revolute(I_A, I_T, 1.0, phi, THETA_DOT, 0.5)
    late = ex["time"] > 0.1  # after generalized-α's start-up transient of the multipliers
    ref_ex = bearing_torque(ex["time"][late], I_A, I_T, phi, THETA_DOT)
    # generalized-α, 2nd order, h = 2⁻¹²: (h θ̇)² ≈ 6e-6 of scale bounds the multiplier error
    err_ex = np.max(np.abs(ex["tau_world"][late] - ref_ex))
    assert err_ex < 6e-6 * scale
    print(
        f"\nphi={phi:.4f}: |tau|max formula {np.abs(ref).max():.6f} N m; "
        f"FMU err {err_fmu:.2e}, Exudyn joint err {err_ex:.2e}"
    )


def test_bearing_torque_zero_at_0_and_half_pi_and_largest_at_45_deg(fmus):
    peak = {}
    for phi in (0.0, np.pi / 4, np.pi / 2):
        peak[phi] = np.abs(run_bar(fmus["skewed_bar"], phi, T=0.2).vector("tau_bearing")).max()
    assert peak[0.0] < 1e-12 and peak[np.pi / 2] < 1e-12
    assert peak[np.pi / 4] == pytest.approx((I_T - I_A) * THETA_DOT**2 / 2, rel=1e-12)


def test_shaft_rate_is_held(fmus):
    res = run_bar(fmus["skewed_bar"], np.pi / 6)
    w = res.vector("w_world")
    assert np.max(np.abs(w - [THETA_DOT, 0.0, 0.0])) < 1e-12 * THETA_DOT * res.n_steps


def arm_reference(t):
    s, c = np.sin(np.pi / 3), np.cos(np.pi / 3)
    return arm_wrist(t, Omega=1.0, omega=2.0, L=0.3, l=0.25, J=[0, 0, 1], i_A0=[s, 0, c], i_F0=[c, 0, -s])


def test_arm_wrist_velocity_and_acceleration(fmus):
    sc = load_scene("two_frame_arm")
    res = run_fmu(fmus["two_frame_arm"], sc)
    ref = arm_reference(res.time)
    errs = {k: np.max(np.abs(res.vector(f"sensor_{k}") - ref[k])) for k in ("r", "v", "a")}
    print(f"\ntwo_frame_arm FMU vs lecture formula over {sc.stop_time} s: {errs}")
    # RK4, h = 1e-3, |ω| ≈ 2.2 rad/s: global error ~ T·(h|ω|)⁴·|ω| ≈ 5e-11; positions ~0.4 m
    for k in errs:
        assert errs[k] < 1e-9
    ex = exudyn_models.simulate_scene(sc, stop_time=2.0, h=2.0**-10)
    ref_ex = arm_reference(ex["time"])
    for k in ("r", "v", "a"):
        # RK67 at h·|ω| ≈ 2e-3 is at round-off level; Exudyn's own body outputs at the point.
        # Exudyn has accelerations only once its solver has taken a step: skip t = 0 for "a".
        first = 1 if k == "a" else 0
        assert np.max(np.abs(ex[f"sensor_{k}"][first:] - ref_ex[k][first:])) < 1e-9
