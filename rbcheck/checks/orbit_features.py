r"""The checks of the orbit (gravity gradient) and of the central field for any scene, with tolerances.

Run by ``rbfmu check`` for a scene that uses these features and has no check of its own
(rbcheck.checks.feature_table):

* orbit: the Jacobi integral E_jacobi is constant (docs/theory.md §9.3) and equals numpy's
  formula (rbcheck.closed_forms.gravity_gradient, without rotors); Exudyn's orbit model
  (rbcheck.exudyn.orbit: a free body with the gravity-gradient torque as a load user
  function) over one orbit; the pitch libration frequency n √(3 (I_x − I_z)/(I_y − J)) (§9.5;
  J the axial inertia of free wheels along the orbit normal) where the scene starts near
  the orbit frame;
* central field: E_total and L_total constant (§9.7), and the Runge–Lenz (eccentricity)
  vector e = v × (x × v)/μ − x/|x| against the scipy reference's (for a point mass it is
  constant; the body's quadrupole moves it slightly, which the reference has too).

Tolerances as in rbcheck.checks.feature_checks. Units SI.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from modelsrc.scene import Scene

from ..baselines.motion import integrate
from ..closed_forms import gravity_gradient as gg
from ..exudyn.orbit import simulate_orbit
from .common import NotApplicable, run
from .feature_checks import ROUND_OFF, aligned, fine_run, fmu_bound, needed
from .orbit import fit_frequencies
from .registry import GenericOutcome, Row, horizon

__all__ = [
    "NEAR_ORBIT_FRAME",
    "central_invariants_check",
    "jacobi_check",
    "orbit_exudyn_check",
    "pitch_libration_check",
    "runge_lenz_check",
]

NAN = float("nan")
# rad: "near the orbit frame": every angle relative to LVLH below this, so that the pitch
# frequency's amplitude shift (the pendulum in 2θ: (2θ)²/16 = θ²/4 relative) stays below 0.3 %
NEAR_ORBIT_FRAME = 0.1
PITCH_PERIODS = 3.0  # the fit needs at least this many pitch periods in the scene's run
EXUDYN_ORBIT_H = (10.0, 5.0)  # s: Exudyn RK67's steps (n h = 0.012 in a 90 min orbit: error ~1e-13)


def _principal(scene: Scene) -> NDArray[np.float64]:
    I = np.asarray(scene.inertia, dtype=float)
    if np.count_nonzero(I - np.diag(np.diag(I))):
        raise NotApplicable("the inertia is not diagonal in body axes (the orbit's closed forms need principal axes)")
    return np.diag(I).copy()


def jacobi_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """max_t |E_J − E_J(0)| relative to n² tr I + max E_kin (the size of its terms, rotors'
    energy included), and without rotors |E_J − numpy's E_J| along the run (round-off only)."""
    if not scene.has("gravity_gradient"):
        raise NotApplicable("no gravity-gradient torque: the body is torque-free in its orbit (see the drift rows)")
    T = horizon(scene, quick)
    r = run(fmu_path, scene, stop_time=T)
    needed(r, "E_jacobi", "E_kin")
    n = float(scene.orbit_rate)
    E = r.values["E_jacobi"]
    scale = n * n * float(np.trace(scene.inertia)) + float(np.max(np.abs(r.values["E_kin"])))
    rows = [
        Row("orbit: max|E_jacobi - E_jacobi(0)| / (n^2 tr I + max E_kin)", "-",
            float(np.max(np.abs(E - E[0]))) / scale, NAN, 0.0, fmu_bound(scene, T)),
    ]  # fmt: skip
    if not scene.rotors and not scene.features - {"orbit", "gravity_gradient"}:
        E_np = gg.jacobi_integral(n, _principal(scene), r.vector("q"), r.vector("w_body"), r.time)
        rows.append(
            Row("orbit: max|E_jacobi - numpy's formula| / (n^2 tr I + max E_kin)", "-",
                float(np.max(np.abs(E - E_np))) / scale, NAN, 0.0, 1e3 * np.finfo(float).eps)
        )  # fmt: skip
    return GenericOutcome(rows=rows, note="E_jacobi: conserved in the orbit frame (docs/theory.md §9.3)")


def orbit_exudyn_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """The FMU against Exudyn's orbit model (rbcheck.exudyn.orbit) over min(T, one orbit): q and
    ω/n; allowed 3 x (Exudyn's own estimate, RK67 at h and h/2, plus the FMU's, from a run at a
    tighter setting: `fine_run`) plus 1e-12 of the size."""
    other = sorted(scene.features - {"orbit", "gravity_gradient"})
    if scene.rotors or other or not scene.has("gravity_gradient"):
        what = other + (["rotors"] if scene.rotors else []) or ["no gravity-gradient torque"]
        raise NotApplicable(
            f"Exudyn's orbit model has the gravity-gradient torque alone; the scene has {', '.join(what)}"
        )
    n = float(scene.orbit_rate)
    T = min(horizon(scene, quick), 2 * math.pi / n)
    r = run(fmu_path, scene, stop_time=T)
    e1, e2 = (simulate_orbit(scene, stop_time=T, h=h) for h in EXUDYN_ORBIT_H)
    if e1["q"].shape != r.vector("q").shape:
        raise ValueError("the FMU's and Exudyn's communication grids differ")
    fine, factor = fine_run(fmu_path, scene, T)
    q = r.vector("q")
    q1, q2, qf = aligned(e1["q"], q), aligned(e2["q"], q), aligned(fine.vector("q"), q)
    dq, eq = float(np.max(np.abs(q - q2))), float(np.max(np.abs(q1 - q2)))
    fq = factor * float(np.max(np.abs(q - qf)))
    w = r.vector("w_body")
    dw = float(np.max(np.abs(w - e2["w_body"]))) / n
    ew = float(np.max(np.abs(e1["w_body"] - e2["w_body"]))) / n
    fw = factor * float(np.max(np.abs(w - fine.vector("w_body")))) / n
    w_scale = float(np.max(np.abs(w))) / n
    rows = [
        Row(f"orbit: max|q - q_Exudyn| over {T:.0f} s", "-", dq, eq, 0.0, 3.0 * (eq + fq) + ROUND_OFF),
        Row(f"orbit: max|w - w_Exudyn| / n over {T:.0f} s", "-", dw, ew, 0.0, 3.0 * (ew + fw) + ROUND_OFF * w_scale),
    ]
    note = (
        f"Exudyn: free body with the gravity-gradient load (rbcheck.exudyn.orbit), RK67 h = {EXUDYN_ORBIT_H[1]:g} s; "
        f"its column: |x(h = {EXUDYN_ORBIT_H[0]:g} s) - x(h = {EXUDYN_ORBIT_H[1]:g} s)|"
    )
    return GenericOutcome(rows=rows, note=note)


def free_wheel_J(scene: Scene) -> float:
    """Σ J [kg m²] of the rotors along ±y (the orbit normal at rest in LVLH), torque mode, no
    motor torque scheduled: they keep their absolute spin, so pitch sees I_y − J (docs/theory.md
    §9). NotApplicable for any other rotor (it couples pitch with roll and yaw, or drives it)."""
    J = 0.0
    for name, r in scene.rotors.items():
        g = np.asarray(r.axis, dtype=float)
        if r.speed or f"u_{name}" in scene.inputs or abs(abs(g[1]) - 1.0) > 1e-12:
            raise NotApplicable(
                f"rotor {name!r} is not a free wheel along the orbit normal (body y): the pitch closed form has none"
            )
        J += float(r.J)
    return J


def pitch_libration_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """The pitch libration frequency fitted to rpy_lvlh's pitch over the scene's run (at least
    PITCH_PERIODS periods) against
    n √(3 (I_x − I_z)/(I_y − J)), where the scene starts near the orbit frame (every angle
    and |ω_lvlh|/n below NEAR_ORBIT_FRAME). Allowed: the amplitude shift θ²/4 of the pendulum in 2θ
    and the roll–yaw coupling, both second order: 2 A² relative (A the largest angle of the
    run), plus 1e-7 for the fit."""
    if not scene.has("gravity_gradient"):
        raise NotApplicable("no gravity-gradient torque: no libration")
    I = _principal(scene)
    if scene.features - {"orbit", "gravity_gradient"}:
        raise NotApplicable(f"other torques act ({', '.join(sorted(scene.features - {'orbit', 'gravity_gradient'}))})")
    J = free_wheel_J(scene)
    n = float(scene.orbit_rate)
    if not (I[0] > I[2] and I[1] > J):
        raise NotApplicable(f"I_x <= I_z (or I_y <= J): pitch is not stable about the orbit frame (I = {list(I)})")
    w_p = n * math.sqrt(3.0 * (I[0] - I[2]) / (I[1] - J))
    # the scene's run, or longer: the fit needs PITCH_PERIODS periods (the FMU's orbit runs are cheap)
    T = max(horizon(scene, quick), PITCH_PERIODS * 2 * math.pi / w_p)
    r = run(fmu_path, scene, stop_time=T)
    needed(r, "rpy_lvlh", "w_lvlh")
    rpy, w_rel = r.vector("rpy_lvlh"), r.vector("w_lvlh")
    start = max(float(np.max(np.abs(rpy[0]))), float(np.max(np.abs(w_rel[0]))) / n)
    if start > NEAR_ORBIT_FRAME:
        raise NotApplicable(
            f"the scene starts {start:.3g} rad (or |w_lvlh|/n) from the orbit frame; the closed form is for "
            f"small librations (below {NEAR_ORBIT_FRAME:g})"
        )
    (f,) = fit_frequencies(r.time, rpy[:, 1], 1)
    A = float(np.max(np.abs(rpy)))
    row = Row(f"orbit: pitch libration frequency (I_y - J, J = {J:g})", "rad/s", f, NAN, w_p, w_p * (2 * A * A + 1e-7))
    note = "pitch: n sqrt(3 (I_x - I_z) / (I_y - J)) (rbcheck.closed_forms.gravity_gradient, docs/theory.md §9.5)"
    return GenericOutcome(rows=[row], note=note)


def central_invariants_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """max_t |E_total − E_total(0)| / |E_total(0)| and max_t |L_total − L_total(0)| / |L_total(0)|
    (orbit + spin + rotors, about the central body: docs/theory.md §9.7) without inputs."""
    if scene.input_names or scene.force_points or scene.features - {"translation", "central_gravity"}:
        raise NotApplicable("inputs, forces or other torques act: E_total and L_total are not conserved")
    T = horizon(scene, quick)
    r = run(fmu_path, scene, stop_time=T)
    needed(r, "E_total", "L_total")
    E, L = r.values["E_total"], r.vector("L_total")
    b = fmu_bound(scene, T)
    rows = [
        Row("central field: max|E_total - E_total(0)| / |E_total(0)|", "-",
            float(np.max(np.abs(E - E[0]))) / abs(float(E[0])), NAN, 0.0, b),
        Row("central field: max|L_total - L_total(0)| / |L_total(0)|", "-",
            float(np.max(np.linalg.norm(L - L[0], axis=1))) / float(np.linalg.norm(L[0])), NAN, 0.0, b),
    ]  # fmt: skip
    return GenericOutcome(rows=rows, note="E_total, L_total: conserved in the central field (docs/theory.md §9.7)")


def runge_lenz(mu: float, x: NDArray, v: NDArray) -> NDArray:
    """The eccentricity (Runge–Lenz) vector e = v × (x × v)/μ − x/|x| [-] of each row (x m, v m/s)."""
    h = np.cross(x, v)
    return np.cross(v, h) / mu - x / np.linalg.norm(x, axis=1)[:, None]


def runge_lenz_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """The Runge–Lenz vector of the FMU's centre of mass against the scipy reference's
    (rbcheck.baselines.motion, the quadrupole force included; allowed 3 x both error estimates
    plus 1e-12), and its drift max_t |e − e(0)|
    (0 for a point mass; the row shows the body's quadrupole)."""
    if not scene.has("translation"):
        raise NotApplicable("the centre of mass does not move")
    T = horizon(scene, quick)
    r = run(fmu_path, scene, stop_time=T)
    needed(r, "x_cm", "v_cm")
    mu = float(scene.mu)
    e = runge_lenz(mu, r.vector("x_cm"), r.vector("v_cm"))
    ref, est = (integrate(scene, r.time, rtol=tol) for tol in (1e-13, 1e-12))
    if "v_cm" not in ref.extra:
        raise ValueError("the scipy reference returned no v_cm")
    e_ref = runge_lenz(mu, ref.extra["x_cm"], ref.extra["v_cm"])
    e_est = runge_lenz(mu, est.extra["x_cm"], est.extra["v_cm"])
    fine, factor = fine_run(fmu_path, scene, T)
    e_fine = runge_lenz(mu, fine.vector("x_cm"), fine.vector("v_cm"))
    d, dest = float(np.max(np.abs(e - e_ref))), float(np.max(np.abs(e_est - e_ref)))
    dfmu = factor * float(np.max(np.abs(e - e_fine)))
    rows = [
        Row("central field: max|e_RL - e_RL,scipy| (Runge-Lenz vector)", "-", d, NAN, 0.0,
            3.0 * (dest + dfmu) + ROUND_OFF),
        Row("central field: max|e_RL - e_RL(0)| (0 for a point mass)", "-",
            float(np.max(np.linalg.norm(e - e[0], axis=1))), NAN, 0.0),
    ]  # fmt: skip
    return GenericOutcome(rows=rows, note="Runge-Lenz: e = v x (x x v)/mu - x/|x|, against rbcheck.baselines.motion")
