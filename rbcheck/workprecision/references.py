"""Reference solutions (closed forms, else scipy DOP853) and the error measures: end-time errors, invariant drifts.

References (docs/theory.md §2.3, §4.2, §4.4, §7): the closed forms of rbcheck.closed_forms.free_symmetric,
rbcheck.closed_forms.free_asymmetric, rbcheck.closed_forms.heavy_top and, for a body held at its
rate, rbcheck.closed_forms.uniform_rotation where they apply (with the parabola of
rbcheck.closed_forms.free_flight for a free body in uniform gravity), else scipy DOP853 at
rtol = 3e-14, atol = 1e-16 on the numpy equations of rbcheck.baselines.rigid_body and
rbcheck.baselines.motion. Each reference carries an estimate of its own error
(`Reference.floor`). A free body's error includes its centre of mass: e_x / X, X the
largest distance it travels from its start.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from modelsrc.errors import ModelInputError
from modelsrc.scene import Scene

from ..baselines.motion import integrate
from ..closed_forms.free_flight import parabola
from ..closed_forms.of_scene import NoClosedForm, closed_rotation, parabola_applies
from ..numerics.rotation_np import quat_to_matrix, rotation_angle_between


@dataclass
class Reference:
    """Reference states at the communication points: w (n,3) rad/s body, q (n,4), and for
    a free body x (n,3) m, the centre of mass (None otherwise); `source` names it;
    `floor` estimates its own headline error (dimensionless); x_scale (m): the largest
    distance of x from its start; rotor_scale (rad/s): the largest |Ω| of a rotor relative
    to the body (0 without rotors)."""

    time: np.ndarray
    w: np.ndarray
    q: np.ndarray
    source: str
    floor: float
    omega_scale: float
    wall: float
    x: np.ndarray | None = None
    x_scale: float = float("nan")
    rotor_scale: float = 0.0


def _gravity_only(scene: Scene) -> bool:
    """Gravity is the only torque (a frictionless top on a pivot): E_total is conserved
    (Scene.conserves_energy) and the body is not torque-free, without a prescribed rate's
    bearing torque (docs/theory.md §4.2)."""
    return scene.conserves_energy and not scene.torque_free and not scene.has("prescribed_rate")


def closed_form(scene: Scene, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, str] | None:
    """Closed-form (w, q, name) at times t where one applies
    (rbcheck.closed_forms.of_scene.closed_rotation: a held rate, a torque-free body with
    diagonal inertia, a frictionless Lagrange top), and for a body in free flight only where
    its centre of mass follows the parabola (`parabola_applies`: no force but uniform
    gravity), which `make_reference` adds; None otherwise."""
    if scene.has("translation") and not parabola_applies(scene):
        return None  # forces push the centre of mass: scipy gives it
    try:
        w, q, name = closed_rotation(scene, t)
    except NoClosedForm:
        return None
    return w, q, f"closed form {name}"


def errors(w: np.ndarray, q: np.ndarray, ref: Reference, x: np.ndarray | None = None) -> tuple[float, float, float]:
    """(e_ω rad/s, e_R rad, headline e) at the last communication point; for a free body
    (ref.x and x given: centre of mass, m) e also bounds e_x / X (X = ref.x_scale)."""
    e_w = float(np.max(np.abs(np.asarray(w)[-1] - ref.w[-1])))
    e_R = float(rotation_angle_between(quat_to_matrix(np.asarray(q)[-1]), quat_to_matrix(ref.q[-1])))
    e = max(e_w / ref.omega_scale, e_R)
    if ref.x is not None and x is not None:
        e = max(e, float(np.max(np.abs(np.asarray(x)[-1] - ref.x[-1]))) / ref.x_scale)
    return e_w, e_R, e


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
    # the method curves measure each integrator on the input it is given: held per step, as
    # the FmuDriver gives it (harness.py); the hold's own error is in forced_inputs' scene table
    fine = integrate(scene, grid, "DOP853", rtol=REF_RTOL, atol=REF_ATOL, inputs="hold")
    x = other_x = None
    if cf is not None:
        w, q, src = cf
        other_w, other_q = fine.w_body, fine.q
        if scene.has("translation"):
            x, _ = parabola(scene.x0, scene.v0, scene.g if scene.has("gravity") else np.zeros(3), grid)
            src += " + parabola rbcheck.closed_forms.free_flight"
            other_x = fine.extra["x_cm"]
    else:
        coarse = integrate(scene, grid, "DOP853", rtol=CHECK_RTOL, atol=CHECK_ATOL, inputs="hold")
        w, q, src = fine.w_body, fine.q, f"scipy DOP853, rtol {REF_RTOL:g}, atol {REF_ATOL:g}"
        other_w, other_q = coarse.w_body, coarse.q
        if scene.has("translation"):
            x, other_x = fine.extra["x_cm"], coarse.extra["x_cm"]
    omega = float(np.max(np.abs(w)))
    if not omega > 0:
        raise ModelInputError(
            f"scene {scene.name}: its reference never turns (max |ω| = 0 over the run): the error e = max(e_ω/Ω, e_R) "
            "has no scale Ω; give it a start rate or inputs that turn it"
        )
    ref = Reference(np.asarray(grid, float), np.asarray(w), np.asarray(q), src, 0.0, omega, 0.0)
    if x is not None:
        ref.x, ref.x_scale = np.asarray(x), float(np.max(np.linalg.norm(x - x[0], axis=1)))
    if "Omega" in fine.extra:  # rotors (rbcheck.baselines.gyrostat)
        ref.rotor_scale = float(np.max(np.abs(fine.extra["Omega"]), initial=0.0))
    ref.floor = errors(other_w, other_q, ref, other_x)[2]
    ref.wall = time.perf_counter() - tic
    return ref


def conserved_quantities(scene: Scene) -> tuple[str | None, str | None]:
    """(energy output, momentum measure) the scene conserves: ("E_kin", "|L|") for a free
    body, ("E_total", "|L|") for one in free flight (translation, gravity only: E_kin
    changes, §7.1), ("E_total", "Lz") for a frictionless top on a pivot (p_φ =
    L_world·e_z, §4.2), (None, None) when torques, forces or friction act; motors (a rotor's
    motor torque or prescribed speed) do work, so then no energy (§8.2); in a central field
    ("E_total", None): its conserved momentum is L_total, which these callers do not read (§9.7)."""
    if scene.has("central_gravity"):
        return ("E_total" if scene.conserves_energy else None), None
    if scene.has("translation"):
        return ("E_total", "|L|") if scene.torque_free and scene.conserves_energy else (None, None)
    if scene.torque_free:
        return ("E_kin" if scene.conserves_energy else None), "|L|"
    if _gravity_only(scene) and np.allclose(np.asarray(scene.g)[:2], 0):
        return "E_total", "Lz"
    return None, None


def drifts(
    scene: Scene, E: np.ndarray | None, L: np.ndarray | None, qn: np.ndarray | None
) -> tuple[float, float, float]:
    """(relative E drift, relative L drift, max ||q| − 1|) over the samples; NaN if n/a
    (the L drift also when L(0) = 0: nothing to be relative to, as in a slew from rest)."""
    e_name, l_name = conserved_quantities(scene)
    dE = dL = dq = float("nan")
    if e_name and E is not None:
        dE = float(np.max(np.abs(E - E[0])) / abs(E[0]))
    if l_name and L is not None:
        L = np.asarray(L)
        if l_name == "|L|":
            n = np.linalg.norm(L, axis=1)
            dL = float(np.max(np.abs(n - n[0])) / n[0]) if n[0] > 0 else float("nan")
        else:
            dL = float(np.max(np.abs(L[:, 2] - L[0, 2])) / np.linalg.norm(L[0]))
    if qn is not None:
        dq = float(np.max(np.abs(np.asarray(qn) - 1.0)))
    return dE, dL, dq
