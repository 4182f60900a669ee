"""Closed forms of the moving reference point: free flight, impulse, the top on an accelerating pivot.

Independent of the FMU (numpy and the closed forms of rbcheck only; a scene is read as
data). SI units; positions x (m), velocities v (m/s), accelerations (m/s²), forces (N)
and momenta (N·s) in the world frame; q unit quaternion (w, x, y, z) body -> world;
w body angular velocity (rad/s).

* `parabola`: the centre of mass of a body in uniform gravity g and no other force,
  x(t) = x0 + v0 t + ½ g t², v = v0 + g t (MIT 2.003J, "Linear momentum for rigid
  bodies": Σ F = M a_C); the rotation about the centre of mass is then torque-free
  (rbcheck.closed_forms.free_asymmetric, rbcheck.closed_forms.free_symmetric).
* `impulse`: linear momentum p(t) − p(0) = ∫ F dt of a world force held piecewise
  constant, exact.
* `accelerating_pivot_top`: a heavy symmetric top whose pivot accelerates at a constant
  a. About the moving pivot B Euler's equations gain M r_C × a_B (docs/theory.md §7.3),
  so the top turns exactly as a Lagrange top in the gravity g − a; the closed form of
  rbcheck.closed_forms.heavy_top applies in a world frame turned so that g − a points down.
* `held_pivot_motion`, `shaker_position_bound`: the pivot of the shaker, whose
  acceleration A ω² cos ωt is held over each communication step at its mean.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..numerics.rotation_np import matrix_to_quat, quat_mul
from . import heavy_top as ht

__all__ = [
    "accelerating_pivot_top",
    "harmonic_motion",
    "held_pivot_motion",
    "impulse",
    "parabola",
    "shaker_position_bound",
    "turn_to_down",
]


def parabola(x0: ArrayLike, v0: ArrayLike, g: ArrayLike, t: ArrayLike) -> tuple[NDArray, NDArray]:
    """Position (n, 3) m and velocity (n, 3) m/s of a point mass in uniform gravity g
    (m/s²) from x0 (m), v0 (m/s) at times t (s)."""
    t = np.asarray(t, dtype=float)[:, None]
    x0, v0, g = (np.asarray(v, dtype=float).reshape(1, 3) for v in (x0, v0, g))
    return x0 + v0 * t + 0.5 * g * t * t, v0 + g * t


def impulse(grid: ArrayLike, forces: ArrayLike) -> NDArray:
    """∫ F dt (N·s, (n, 3)) at the points of `grid` (s, (n,)) of a force held at
    forces[k] (N, (n−1, 3)) over [grid[k], grid[k+1]]: the change of linear momentum."""
    grid = np.asarray(grid, dtype=float)
    F = np.asarray(forces, dtype=float).reshape(len(grid) - 1, 3)
    steps = np.diff(grid)[:, None] * F
    return np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])


def turn_to_down(g_eff: ArrayLike) -> NDArray:
    """A rotation Q (3×3, det +1) with Q g_eff = (0, 0, −|g_eff|): it turns the world so
    that the effective gravity points down its z axis."""
    d = np.asarray(g_eff, dtype=float).reshape(3)
    n = float(np.linalg.norm(d))
    if not n > 0.0:
        raise ValueError(f"the effective gravity g - a must not vanish, got {d.tolist()}")
    u = -d / n  # the direction that becomes +z
    e = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(e, u)
    x /= np.linalg.norm(x)
    y = np.cross(u, x)
    return np.vstack([x, y, u])  # rows: new axes in old coordinates


def accelerating_pivot_top(
    I_cm: ArrayLike,
    mass: float,
    r_cm: ArrayLike,
    g: ArrayLike,
    a: ArrayLike,
    q0: ArrayLike,
    w0: ArrayLike,
    t: ArrayLike,
) -> tuple[NDArray, NDArray]:
    """Body rate w (n, 3) rad/s and attitude q (n, 4) of a symmetric top (I_cm =
    diag(I1, I1, I3) kg m², centre of mass r_cm = (0, 0, l) m from the pivot, mass kg)
    whose pivot accelerates at the constant a (m/s², world), in gravity g (m/s², world),
    from q0, w0 (body) at times t (s): the Lagrange top in gravity g − a (docs/theory.md
    §7.3), rbcheck.closed_forms.heavy_top in the world turned by `turn_to_down`."""
    I = np.asarray(I_cm, dtype=float)
    r = np.asarray(r_cm, dtype=float)
    if I[0, 0] != I[1, 1] or np.any(I[~np.eye(3, dtype=bool)] != 0.0) or r[0] != 0.0 or r[1] != 0.0 or not r[2] > 0:
        raise ValueError(f"needs diag(I1, I1, I3) and r_cm = (0, 0, l > 0), got {I.tolist()}, {r.tolist()}")
    g_eff = np.asarray(g, dtype=float) - np.asarray(a, dtype=float)
    Q = turn_to_down(g_eff)
    qQ = matrix_to_quat(Q)
    l = float(r[2])
    P = ht.TopParams(
        I1=float(I[0, 0]) + mass * l * l, I3=float(I[2, 2]), M=float(mass), g=float(np.linalg.norm(g_eff)), l=l
    )
    top = ht.HeavyTop(P, ht.init_from_state(quat_mul(qQ, np.asarray(q0, dtype=float)), w0))
    qt = top.quaternion(t)
    q_world = quat_mul(np.broadcast_to(np.array([qQ[0], -qQ[1], -qQ[2], -qQ[3]]), qt.shape), qt)
    return top.omega(t), q_world


def held_pivot_motion(
    grid: ArrayLike, accelerations: ArrayLike, x0: ArrayLike, v0: ArrayLike
) -> tuple[NDArray, NDArray]:
    """Pivot position (n, 3) m and velocity (n, 3) m/s at the points of `grid` (s) when
    its acceleration is held at accelerations[k] (m/s², (n−1, 3)) over each step, from
    x0, v0: the exact double integral, x_{k+1} = x_k + H v_k + ½ H² a_k, v_{k+1} = v_k + H a_k."""
    grid = np.asarray(grid, dtype=float)
    acc = np.asarray(accelerations, dtype=float).reshape(len(grid) - 1, 3)
    x = np.empty((len(grid), 3))
    v = np.empty((len(grid), 3))
    x[0], v[0] = x0, v0
    for k, H in enumerate(np.diff(grid)):
        x[k + 1] = x[k] + H * v[k] + 0.5 * H * H * acc[k]
        v[k + 1] = v[k] + H * acc[k]
    return x, v


def harmonic_motion(
    amplitude: ArrayLike, omega: float, phase: float, x0: ArrayLike, v0: ArrayLike, t: ArrayLike
) -> tuple[NDArray, NDArray]:
    """Position (n, 3) m and velocity (n, 3) m/s of a point whose acceleration is
    amplitude · cos(ω t + φ) (m/s², world; ω rad/s, φ rad), from x0, v0 at times t (s):
    v = v0 + (A/ω)(sin(ω t + φ) − sin φ), x = x0 + (v0 − (A/ω) sin φ) t − (A/ω²)(cos(ω t + φ) − cos φ)."""
    t = np.asarray(t, dtype=float)[:, None]
    A = np.asarray(amplitude, dtype=float).reshape(1, 3)
    x0, v0 = np.asarray(x0, dtype=float).reshape(1, 3), np.asarray(v0, dtype=float).reshape(1, 3)
    s0, c0 = np.sin(phase), np.cos(phase)
    v = v0 + A / omega * (np.sin(omega * t + phase) - s0)
    x = x0 + (v0 - A / omega * s0) * t - A / omega**2 * (np.cos(omega * t + phase) - c0)
    return x, v


def shaker_position_bound(amplitude: float, omega: float, H: float) -> float:
    """Bound (m) of |x_held − (−A cos ωt)| for the shaker pivot whose acceleration
    A ω² cos ωt (amplitude = A ω², m/s²) is held at its mean over steps of H (s).

    Holding the mean makes the velocity exact at every communication point; per step the
    position then errs by ∫ (t_{k+1} − s − H/2) a(s) ds = −H³ ȧ(t_m)/12 + O(H⁵) (t_m the
    mid-step), which sums to −H²/12 (a(t) − a(0)): at most H² · 2 A ω²/12 = H² A ω²/6,
    with 10 % margin for the O(H⁵) rest."""
    return 1.1 * H * H * abs(amplitude) / 6.0
