"""Reference solutions (closed forms, else scipy DOP853) and the error measures: end-time errors, invariant drifts.

References (docs/theory.md §2.3, §4.2): the closed forms of rbcheck.free_symmetric,
rbcheck.free_asymmetric, rbcheck.heavy_top where they apply, else scipy DOP853 at
rtol = 3e-14, atol = 1e-16 on the numpy equations of rbcheck.baselines. Each reference
carries an estimate of its own error (`Reference.floor`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from modelsrc.scene import Scene

from .. import free_asymmetric, free_symmetric, heavy_top
from ..baselines import integrate_scipy
from ..rotation_np import quat_to_matrix, rotation_angle_between


@dataclass
class Reference:
    """Reference states at the communication points: w (n,3) rad/s body, q (n,4);
    `source` names it; `floor` estimates its own headline error (dimensionless)."""

    time: np.ndarray
    w: np.ndarray
    q: np.ndarray
    source: str
    floor: float
    omega_scale: float
    wall: float


def _gravity_only(scene: Scene) -> bool:
    """Gravity is the only torque (a frictionless top on a pivot): E_total is conserved
    (Scene.conserves_energy) and the body is not torque-free, without a prescribed rate's
    bearing torque (docs/theory.md §4.2)."""
    return scene.conserves_energy and not scene.torque_free and not scene.has("prescribed_rate")


def closed_form(scene: Scene, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, str] | None:
    """Closed-form (w, q, name) at times t where one applies (docs/theory.md §2.3, §4.2):
    torque-free symmetric (I1 = I2) or asymmetric principal body, or the Lagrange top
    (I1 = I2 about the centre of mass, r_cm on e3 above the pivot, g along −e_z, no
    friction, no torque inputs). None otherwise."""
    I = np.asarray(scene.inertia, dtype=float)
    if not np.allclose(I, np.diag(np.diag(I)), rtol=0, atol=1e-15 * np.abs(I).max()):
        return None
    d = np.diag(I)
    if scene.torque_free:
        if d[0] == d[1]:
            w, q = free_symmetric.solve(d[0], d[2], scene.w0, scene.q0, t)
            return w, q, "closed form rbcheck.free_symmetric"
        if len(set(d.tolist())) == 3:
            w, q = free_asymmetric.solve(d, scene.w0, scene.q0, t)
            return w, q, "closed form rbcheck.free_asymmetric"
        return None
    if _gravity_only(scene) and d[0] == d[1]:
        r, g = np.asarray(scene.r_cm, float), np.asarray(scene.g, float)
        if r[0] == r[1] == 0 and r[2] > 0 and g[0] == g[1] == 0 and g[2] < 0:
            l, M = float(r[2]), float(scene.mass)
            # transverse moment about the pivot (parallel-axis theorem, docs/theory.md §3.2)
            P = heavy_top.TopParams(I1=d[0] + M * l * l, I3=d[2], M=M, g=-float(g[2]), l=l)
            top = heavy_top.HeavyTop(P, heavy_top.init_from_state(scene.q0, scene.w0))
            return top.omega(t), top.quaternion(t), "closed form rbcheck.heavy_top"
    return None


def errors(w: np.ndarray, q: np.ndarray, ref: Reference) -> tuple[float, float, float]:
    """(e_ω rad/s, e_R rad, headline e) at the last communication point."""
    e_w = float(np.max(np.abs(np.asarray(w)[-1] - ref.w[-1])))
    e_R = float(rotation_angle_between(quat_to_matrix(np.asarray(q)[-1]), quat_to_matrix(ref.q[-1])))
    return e_w, e_R, max(e_w / ref.omega_scale, e_R)


# The reference run (scipy refuses rtol < 100 eps = 2.2e-14) and the coarser run whose
# distance to it estimates the reference's own error.
REF_RTOL, REF_ATOL = 3e-14, 1e-16
CHECK_RTOL, CHECK_ATOL = 3e-13, 1e-15


def make_reference(scene: Scene, grid: np.ndarray) -> Reference:
    """The scene's reference at the grid points, with an estimate of its own error:
    for a closed form, its distance to DOP853 at rtol 3e-14; for DOP853 at rtol 3e-14,
    its distance to DOP853 at rtol 3e-13 (an over-estimate: DOP853's error scales about
    linearly with rtol, so the finer run is ~10x better than this difference)."""
    tic = time.perf_counter()
    cf = closed_form(scene, grid)
    fine = integrate_scipy(scene, grid, "DOP853", rtol=REF_RTOL, atol=REF_ATOL)
    if cf is not None:
        w, q, src = cf
        other_w, other_q = fine.w_body, fine.q
    else:
        coarse = integrate_scipy(scene, grid, "DOP853", rtol=CHECK_RTOL, atol=CHECK_ATOL)
        w, q, src = fine.w_body, fine.q, f"scipy DOP853, rtol {REF_RTOL:g}, atol {REF_ATOL:g}"
        other_w, other_q = coarse.w_body, coarse.q
    omega = float(np.max(np.abs(w)))
    if not omega > 0:
        raise ValueError(f"scene {scene.name}: the reference never rotates (max |ω| = 0), no error scale")
    ref = Reference(np.asarray(grid, float), np.asarray(w), np.asarray(q), src, 0.0, omega, 0.0)
    ref.floor = errors(other_w, other_q, ref)[2]
    ref.wall = time.perf_counter() - tic
    return ref


def conserved_quantities(scene: Scene) -> tuple[str | None, str | None]:
    """(energy output, momentum measure) the scene conserves: ("E_kin", "|L|") for a free
    body, ("E_total", "Lz") for a frictionless top on a pivot (p_φ = L_world·e_z, §4.2),
    (None, None) when torques or friction act."""
    if scene.torque_free:
        return "E_kin", "|L|"
    if _gravity_only(scene) and np.allclose(np.asarray(scene.g)[:2], 0):
        return "E_total", "Lz"
    return None, None


def drifts(
    scene: Scene, E: np.ndarray | None, L: np.ndarray | None, qn: np.ndarray | None
) -> tuple[float, float, float]:
    """(relative E drift, relative L drift, max ||q| − 1|) over the samples; NaN if n/a."""
    e_name, l_name = conserved_quantities(scene)
    dE = dL = dq = float("nan")
    if e_name and E is not None:
        dE = float(np.max(np.abs(E - E[0])) / abs(E[0]))
    if l_name and L is not None:
        L = np.asarray(L)
        if l_name == "|L|":
            n = np.linalg.norm(L, axis=1)
            dL = float(np.max(np.abs(n - n[0])) / n[0])
        else:
            dL = float(np.max(np.abs(L[:, 2] - L[0, 2])) / np.linalg.norm(L[0]))
    if qn is not None:
        dq = float(np.max(np.abs(np.asarray(qn) - 1.0)))
    return dE, dL, dq
