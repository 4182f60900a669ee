"""Fast accuracy checks on a free body with a full inertia tensor: error control at a coarse step, the gyroscopic term.

Issue 39 item 4: two small equation errors were seen only by slow or indirect tests, an error
estimate of step-size control ten times too small and the products of inertia dropped from the
gyroscopic term ω × (I ω). Both are checked here in about a second, against Euler's equations
I ω̇ = −ω × (I ω), q̇ = ½ q ⊗ (0, ω) (docs/theory.md §2.1, §2.2) written out in this file and
integrated by scipy's DOP853 at rtol 1e-13, far below the tolerances tested.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from fmu.build.build_fmu import build_fmu
from modelsrc.scene import load_scene
from rbcheck.numerics.rotation_np import quat_to_matrix, rotation_angle_between

from ..harness.control_harness import library, simulate
from ..harness.fmi3_ctypes import OK
from ..harness.scenes import write_scene

# kg m²: principal moments 1, 2, 3 turned about a skew axis, so that all three products are
# non-zero (I12 = 0.3, I13 = −0.2, I23 = 0.25); positive definite, triangle inequality holds.
INERTIA = np.array([[1.5, 0.3, -0.2], [0.3, 2.0, 0.25], [-0.2, 0.25, 2.5]])
W0 = np.array([3.0, 10.0, 2.0])  # rad/s, body: a fast tumble about all three axes (steps well below H)
T, H = 2.0, 0.5  # s: end time and the coarse communication step (4 doSteps)

SCENE = f"""
name = "full_tensor_free"
description = "Torque-free body whose inertia tensor has three non-zero products of inertia."
outputs = ["q", "w_body"]
[body]
inertia = {[[float(v) for v in row] for row in INERTIA]}
[initial]
w_body = {[float(v) for v in W0]}
"""


def euler_reference(t_end: float) -> tuple[np.ndarray, np.ndarray]:
    """ω (rad/s, body) and q (scalar first, body -> world) at t_end from q = (1, 0, 0, 0), ω = W0,
    by DOP853 on I ω̇ = −ω × (I ω), q̇ = ½ q ⊗ (0, ω)."""
    I_inv = np.linalg.inv(INERTIA)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        q, w = y[:4], y[4:]
        w_dot = I_inv @ -np.cross(w, INERTIA @ w)
        q0, qv = q[0], q[1:]
        q_dot = 0.5 * np.concatenate(([-qv @ w], q0 * w + np.cross(qv, w)))
        return np.concatenate((q_dot, w_dot))

    y0 = np.concatenate(([1.0, 0.0, 0.0, 0.0], W0))
    sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-15)
    q = sol.y[:4, -1]
    return sol.y[4:, -1], q / np.linalg.norm(q)


def end_error(run, w_ref: np.ndarray, q_ref: np.ndarray) -> float:
    """max(|ω − ω_ref|∞ / |ω_ref|, attitude angle between q and q_ref in rad) at the end."""
    w, q = run.w[-1], run.q[-1]
    dw = float(np.max(np.abs(w - w_ref)) / np.linalg.norm(w_ref))
    return max(dw, float(rotation_angle_between(quat_to_matrix(q), quat_to_matrix(q_ref))))


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    out = tmp_path_factory.mktemp("full_tensor")
    scene = load_scene(write_scene(out, SCENE, "full_tensor_free"))
    assert not scene.diagonal  # the full-tensor equations, not the principal-axis ones
    return library(build_fmu(scene, out))


@pytest.fixture(scope="module")
def reference():
    return euler_reference(T)


# DOP853's estimate (a blend of its order-5 and order-3 differences) over-states the error of its
# order-8 solution: on this body err / (tol·T) measured 0.071 (tol 1e-6) and 0.058 (1e-8), so the
# promise err ≤ 3 tol·T (docs/theory.md §5.5; band ≤ 1.9 over the shipped scenes,
# tests/physics/test_error_control.py) alone would not see an estimate ten times too small (measured
# then: 0.84 and 0.70). The bound of this body is 0.3 tol·T: four times its measured ratio.
BODY_BAND = 0.3


@pytest.mark.parametrize("tol", [1e-6, 1e-8])
def test_error_controlled_coarse_step_keeps_error_within_tolerance_times_t(lib, reference, tol):
    run = simulate(lib, [H] * round(T / H), {"tolerance": tol, "h_max": 0.0}, "rk8")
    assert run.status == OK, run.log
    err = end_error(run, *reference)
    steps = run.report["internal_steps"].sum()
    print(f"\nrk8 tol {tol:.0e}: error {err:.3e} = {err / (tol * T):.3f} tol·T, {steps:.0f} steps")
    assert steps > 4 * (len(run.time) - 1)  # the control, not the communication step, chose the steps
    assert err <= 3.0 * tol * T
    assert err <= BODY_BAND * tol * T


def test_full_tensor_gyroscopic_term_against_euler_equations(lib, reference):
    # at tol 1e-11 the error is ~tol·T = 2e-11; a gyroscopic term without the products of
    # inertia (ω × diag(I) ω) changes ω̇ by O(|I12|·|ω|²) ~ 0.1 rad/s² and ω(T) by ~0.1
    run = simulate(lib, [H] * round(T / H), {"tolerance": 1e-11, "h_max": 0.0}, "rk8")
    assert run.status == OK, run.log
    w_ref, q_ref = reference
    err = end_error(run, w_ref, q_ref)
    print(f"\nfull tensor vs Euler's equations (DOP853): error {err:.3e}")
    assert err <= 3.0 * 1e-11 * T
    # the motion is not trivial: ω turned well away from its start
    assert np.linalg.norm(w_ref - W0) > 0.1
