"""Torque-free scenes through fmpy against the closed form and the invariants.

Tolerances follow from the method: RK4 has global error C·h⁴, and the quaternion
projection after each step does not lower the order (docs/theory.md §5).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fmu.drive.run import run_fmu
from modelsrc.scene import load_scene
from rbcheck.closed_forms import free_symmetric
from rbcheck.numerics.rotation_np import quat_conj, quat_mul

from ..harness.stepping import rk4_fixed

EPS = np.finfo(float).eps


def attitude_error(q_a: np.ndarray, q_b: np.ndarray) -> float:
    """Rotation angle (rad) between two orientations given as unit quaternions."""
    d = quat_mul(quat_conj(q_a), q_b)
    return float(2 * math.asin(min(1.0, np.linalg.norm(d[1:4]))))


def symmetric_errors(fmu, h: float, T: float = 10.0) -> tuple[float, float]:
    sc = load_scene("symmetric_free")
    res = run_fmu(fmu, sc, stop_time=T, step=0.1, start_values=rk4_fixed(sc, h))
    w_ref, q_ref = free_symmetric.solve(1.0, 1.6, sc.w0, sc.q0, np.array([T]))
    w_err = float(np.max(np.abs(res.vector("w_body")[-1] - w_ref[0])))
    return w_err, attitude_error(q_ref[0], res.vector("q")[-1])


def test_symmetric_free_fourth_order_convergence(fmus):
    h1, h2 = 0.02, 0.01
    (w1, a1), (w2, a2) = symmetric_errors(fmus["symmetric_free"], h1), symmetric_errors(fmus["symmetric_free"], h2)
    print(
        f"\nsymmetric_free T=10: h={h1}: |dw|={w1:.3e} rad/s, attitude {a1:.3e} rad; "
        f"h={h2}: |dw|={w2:.3e}, attitude {a2:.3e}; orders {math.log2(w1 / w2):.3f}, {math.log2(a1 / a2):.3f}"
    )
    # Order from halving h: log2(e(h)/e(h/2)) = 4 + O(h·|ω|); h·|ω| <= 0.02·2.04 -> within ±0.2
    assert 3.8 < math.log2(w1 / w2) < 4.2
    assert 3.8 < math.log2(a1 / a2) < 4.2
    # and the error is the size RK4 predicts, far above round-off: C·h⁴ with C = O(T·|ω|⁵) ≈ 10·36
    assert w2 < 10 * 36 * h2**4 and a2 < 10 * 36 * h2**4


def test_symmetric_free_precession_rate(fmus):
    sc = load_scene("symmetric_free")
    res = run_fmu(fmus["symmetric_free"], sc, stop_time=10.0, start_values=rk4_fixed(sc))
    w = res.vector("w_body")
    # ω1 + iω2 rotates at −Ω with Ω = ω3 (I1 − I3)/I1 (Euler: ω̇1 = Ω ω2, ω̇2 = −Ω ω1)
    phase = np.unwrap(np.angle(w[:, 0] + 1j * w[:, 1]))
    rate = np.polyfit(res.time, phase, 1)[0]
    omega = free_symmetric.precession_rate(1.0, 1.6, sc.w0[2])
    assert rate == pytest.approx(-omega, rel=1e-9)  # RK4 phase error ~ T·(Ωh)⁴/h·h ≈ 1e-11
    assert np.max(np.abs(w[:, 2] - sc.w0[2])) <= 8 * EPS * sc.w0[2]  # ω3 = const: I1 = I2 exactly


@pytest.mark.parametrize("scene", ["free_asymmetric", "symmetric_free"])
def test_free_body_invariants(fmus, scene):
    sc = load_scene(scene)
    res = run_fmu(fmus[scene], sc, start_values=rk4_fixed(sc))
    E = res.values["E_kin"]
    L = res.vector("L_world")
    nsteps = sc.stop_time / sc.fixed_step
    dE = np.max(np.abs(E - E[0])) / E[0]
    dL = np.max(np.linalg.norm(L - L[0], axis=1)) / np.linalg.norm(L[0])
    dq = np.max(np.abs(np.linalg.norm(res.vector("q"), axis=1) - 1))
    print(f"\n{scene}: {nsteps:.0f} RK4 steps: E drift {dE:.2e}, L_world drift {dL:.2e}, max||q|-1| {dq:.2e}")
    # RK4 local error ~ (h|ω|)⁵/120 per step, summed over all steps: |ω| <= 2 rad/s, h = 1e-3
    bound = nsteps * (sc.fixed_step * 2.0) ** 5 / 120 * 10
    assert dE < bound and dL < bound
    assert dq <= 2 * EPS  # normalised after every step


def test_heavy_top_invariants(fmus):
    sc = load_scene("heavy_top")
    res = run_fmu(fmus["heavy_top"], sc, start_values=rk4_fixed(sc))
    E = res.values["E_total"]
    p_phi = res.values["L_world[3]"]  # gravity along world z: L·e_z conserved
    p_psi = res.values["L_body[3]"]  # symmetric top: L·e3 = I3 ω3 conserved
    dE = np.max(np.abs(E - E[0])) / E[0]
    dphi = np.max(np.abs(p_phi - p_phi[0])) / abs(p_psi[0])
    dpsi = np.max(np.abs(p_psi - p_psi[0])) / abs(p_psi[0])
    print(f"\nheavy_top: E drift {dE:.2e}, p_phi drift {dphi:.2e}, p_psi drift {dpsi:.2e}")
    nsteps = sc.stop_time / sc.fixed_step
    bound = nsteps * (sc.fixed_step * 150.0) ** 5 / 120 * 10  # h|ω| = 0.015
    assert dE < bound and dphi < bound
    assert dpsi <= 64 * EPS  # ω̇3 = 0 exactly for I1 = I2 (the gravity torque has no e3 component)
    theta = res.values["euler_zxz[2]"]
    assert theta.min() > 0.29 and theta.max() < 0.5  # nutation between two cones, starting at 0.3 rad
