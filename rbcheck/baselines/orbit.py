"""scipy reference of a rigid body in a circular orbit with the gravity-gradient torque (docs/theory.md §9).

Conventions of rbcheck.closed_forms.gravity_gradient (LVLH, world = LVLH at t = 0,
principal moments along body x, y, z). `reference` integrates q, ω in the inertial frame
with the nadir an explicit function of time, with numpy and scipy's DOP853 (independent of
the CasADi model and its orbit angle). Units SI: rad, rad/s, s, kg·m².
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from ..numerics.rotation_np import quat_mul, quat_to_matrix


def _rhs(n: float, I: NDArray[np.float64]):
    Iinv = 1.0 / I

    def f(t: float, y: np.ndarray) -> np.ndarray:
        q, w = y[:4], y[4:]
        R = quat_to_matrix(q / np.linalg.norm(q))
        c = R.T @ np.array([-math.sin(n * t), 0.0, math.cos(n * t)])  # nadir, body (§9.1)
        tau = 3.0 * n * n * np.cross(c, I * c)
        qd = 0.5 * quat_mul(q, np.concatenate(([0.0], w)))
        return np.concatenate((qd, Iinv * (tau - np.cross(w, I * w))))

    return f


def reference(
    n: float, I: NDArray[np.float64], q0: np.ndarray, w0: np.ndarray, t: np.ndarray, rtol: float = 1e-13
) -> tuple[np.ndarray, np.ndarray]:
    """(q, ω) at the times t (s) of the principal body I (kg·m²) in the orbit of rate n
    (rad/s) with the gravity-gradient torque, from (q0, ω0) at t = 0: scipy DOP853 at rtol,
    atol = rtol · n for ω and rtol for q. Each q is normalised."""
    y0 = np.concatenate((q0, w0)).astype(float)
    atol = np.concatenate((np.full(4, rtol), np.full(3, rtol * n)))
    sol = solve_ivp(_rhs(n, I), (0.0, float(t[-1])), y0, method="DOP853", t_eval=t, rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(f"scipy reference failed: {sol.message}")
    q = sol.y[:4].T
    return q / np.linalg.norm(q, axis=1)[:, None], sol.y[4:].T
