r"""FMU vs Exudyn trajectories and conserved-quantity drifts of any scene, as data.

:func:`fmu_vs_exudyn` co-simulates a scene with its FMU and with the Exudyn model of
:mod:`rbcheck.exudyn.models` and bounds their difference by both sides' Richardson error
estimates; :func:`conserved_drifts` runs the FMU with several methods and step sizes and
measures how far the scene's conserved quantities (or exact balances, with friction)
move (docs/theory.md §2.3, §4.2, §4.3). Which quantities a scene conserves is decided
from its data (:func:`drift_plan`: ``Scene.torque_free``, ``Scene.conserves_energy``).
Units SI; ``w`` = body angular velocity [rad/s]; ``L`` angular momentum [N m s] (about
the pivot for gravity scenes); ``q`` = unit quaternion (w, x, y, z) body -> world.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import cumulative_simpson

from modelsrc.methods import METHODS
from modelsrc.scene import INPUT_OF_FEATURE, Scene
from modelsrc.scene_inputs import zero_after

from ..exudyn.coverage import covers as exudyn_covers
from ..numerics.rotation_np import quat_to_matrix, rotation_angle_between
from .common import NotApplicable, exudyn_run, is_principal_diag, load, method_codes, run

__all__ = [
    "DriftPlan",
    "DriftRow",
    "TrajectoryComparison",
    "conserved_drifts",
    "drift_plan",
    "fmu_vs_exudyn",
]

# Order of Exudyn's solvers, for the Richardson estimates of its error.
EXUDYN_ORDER = {"RK44": 4, "RK67": 6, "TrapezoidalIndex2": 2, "GeneralizedAlpha": 2}
# Features whose torques come from the input tables (they stop where the tables do).
INPUT_FEATURES = frozenset(INPUT_OF_FEATURE)


@dataclass
class TrajectoryComparison:
    """FMU vs Exudyn over [0, stop_time]: max_t |w_fmu - w_exu| [rad/s] and max attitude
    angle between them [rad], and for a moving reference point max_t |x_cm_fmu −
    x_cm_exu| [m] (nan otherwise); est_* = error estimates of each side from a run at
    half the internal step (Richardson: |x_h - x_{h/2}| / (1 - 2^-p), p = the order of
    the scene's default FMU method (4 for RK4), of Exudyn's solver (6 for RK67, 2 for
    the trapezoidal rule of the moving pivot)), same units."""

    scene: str
    stop_time: float
    max_dw: float
    max_dangle: float
    est_fmu_w: float
    est_fmu_angle: float
    est_exu_w: float
    est_exu_angle: float
    w_scale: float
    wall_fmu: float
    wall_exudyn: float
    max_dx: float = float("nan")
    est_fmu_x: float = float("nan")
    est_exu_x: float = float("nan")
    x_scale: float = float("nan")
    exudyn_solver: str = "RK67"

    @property
    def tol_w(self) -> float:
        """Allowed max |dw| [rad/s]: 3 x the sum of both error estimates plus a round-off
        floor of 1e-12 |w| (the estimates themselves are only good to a factor ~2)."""
        return 3.0 * (self.est_fmu_w + self.est_exu_w) + 1e-12 * self.w_scale

    @property
    def tol_angle(self) -> float:
        """Allowed max attitude angle [rad], as tol_w (round-off floor 1e-12 rad)."""
        return 3.0 * (self.est_fmu_angle + self.est_exu_angle) + 1e-12

    @property
    def tol_x(self) -> float:
        """Allowed max |dx_cm| [m], as tol_w (round-off floor 1e-12 of the largest |x_cm|)."""
        return 3.0 * (self.est_fmu_x + self.est_exu_x) + 1e-12 * self.x_scale


def _traj_diff(wa, qa, wb, qb, xa=None, xb=None) -> tuple[float, float, float]:
    dw = float(np.max(np.abs(np.asarray(wa) - np.asarray(wb))))
    da = float(np.max(rotation_angle_between(quat_to_matrix(qa), quat_to_matrix(qb))))
    dx = float("nan") if xa is None else float(np.max(np.abs(np.asarray(xa) - np.asarray(xb))))
    return dw, da, dx


def fmu_vs_exudyn(
    fmu_path: str | Path,
    scene: Scene | str | Path,
    stop_time: float | None = None,
    estimate_errors: bool = True,
    verbose: bool = False,
) -> TrajectoryComparison:
    """Co-simulate the scene (its inputs, start state, h_max, default method) with the FMU
    and with Exudyn RK67 at the same internal step, and compare the trajectories.

    Raises NotApplicable when the Exudyn model lacks one of the scene's features."""
    sc = load(scene)
    if sc.rotors:
        raise NotApplicable(
            "the rigid-body Exudyn model (rbcheck.exudyn.models) has no rotors; the jointed gyrostat of "
            "rbcheck.exudyn.rotors is compared in the rotors' own checks"
        )
    if sc.has("orbit"):
        raise NotApplicable(
            "the rigid-body Exudyn model has no orbit; Exudyn's orbit model (rbcheck.exudyn.orbit) is compared "
            "in the orbit's own checks"
        )
    why = exudyn_covers(sc)
    if why is not None:
        raise NotApplicable(f"{why}: it would simulate another system")
    p = METHODS[sc.method].order
    T = sc.stop_time if stop_time is None else float(stop_time)
    outs = [f"q[{i}]" for i in (1, 2, 3, 4)] + [f"w_body[{i}]" for i in (1, 2, 3)]
    if sc.moves:
        outs += [f"x_cm[{i}]" for i in (1, 2, 3)]
    # the FMU with fixed steps of the scene's fixed step (docs/theory.md §5.4), so that the
    # halved step below estimates its error; Exudyn's step: the same, a quarter of it for
    # an order-2 solver (the trapezoidal rule of the moving pivot), so that its error does
    # not hide the FMU's
    fixed = {"tolerance": 0.0, "h_max": sc.fixed_step}
    t0 = time.perf_counter()
    r = run(fmu_path, sc, stop_time=T, outputs=outs, start_values=fixed)
    wall_f = time.perf_counter() - t0
    h_e = 0.25 * sc.fixed_step if sc.has("moving_pivot") else sc.fixed_step
    t0 = time.perf_counter()
    e = exudyn_run(sc, stop_time=T, h=h_e)
    wall_e = time.perf_counter() - t0
    if e["time"].shape != r.time.shape or np.max(np.abs(e["time"] - r.time)) > 1e-9 * T:
        raise RuntimeError(f"scene {sc.name}: FMU and Exudyn communication grids differ")
    wf, qf = r.vector("w_body"), r.vector("q")
    xf = r.vector("x_cm") if sc.moves else None
    dw, da, dx = _traj_diff(wf, qf, e["w_body"], e["q"], xf, e.get("x_cm"))
    ef_w = ef_a = ee_w = ee_a = ef_x = ee_x = float("nan")
    if estimate_errors:
        r2 = run(fmu_path, sc, stop_time=T, outputs=outs, start_values={"tolerance": 0.0, "h_max": 0.5 * sc.fixed_step})
        d = _traj_diff(wf, qf, r2.vector("w_body"), r2.vector("q"), xf, r2.vector("x_cm") if sc.moves else None)
        ef_w, ef_a, ef_x = (v / (1 - 2.0**-p) for v in d)
        e2 = exudyn_run(sc, stop_time=T, h=0.5 * h_e)
        d = _traj_diff(e["w_body"], e["q"], e2["w_body"], e2["q"], e.get("x_cm"), e2.get("x_cm"))
        pe = EXUDYN_ORDER[e.get("solver", "RK67")]
        ee_w, ee_a, ee_x = (v / (1 - 2.0**-pe) for v in d)
    out = TrajectoryComparison(sc.name, T, dw, da, ef_w, ef_a, ee_w, ee_a, float(np.max(np.abs(wf))), wall_f, wall_e)
    out.exudyn_solver = str(e.get("solver", "RK67"))
    if sc.moves:
        out.max_dx, out.est_fmu_x, out.est_exu_x = dx, ef_x, ee_x
        out.x_scale = float(np.max(np.abs(xf)))
    if verbose:
        print(
            f"{sc.name}: FMU vs Exudyn over {T:g} s: max|dw| {dw:.2e} rad/s (estimates FMU "
            f"{ef_w:.1e}, Exudyn {ee_w:.1e}; tol {out.tol_w:.1e}), max angle {da:.2e} rad "
            f"(estimates {ef_a:.1e}, {ee_a:.1e}; tol {out.tol_angle:.1e})"
            + (f", max|dx_cm| {dx:.2e} m (tol {out.tol_x:.1e})" if sc.moves else "")
            + f"; wall FMU {wall_f:.2f} s, Exudyn {wall_e:.2f} s"
        )
    return out


@dataclass
class DriftRow:
    """Drifts of one FMU run (method, h_max [s]): name -> max over the run of the
    relative deviation from the initial value (or from the exact balance, see
    :func:`conserved_drifts`)."""

    method: str
    h_max: float
    drifts: dict[str, float]
    wall_time: float


def _torque_free_from(sc: Scene) -> float | None:
    """Time [s] after which all of the scene's inputs stay zero (None if never)."""
    t_free = 0.0
    for v in sc.inputs.values():
        t = zero_after(v)
        if t is None:
            return None
        t_free = max(t_free, t)
    return t_free


@dataclass(frozen=True)
class DriftPlan:
    """What :func:`conserved_drifts` measures for a scene. t_from [s]: start of the
    torque-free tail of the input tables (0 without inputs); pivot: a gravity scene
    (E_total, p_phi = L_world . e_up and maybe p_psi; else E_kin, |L|, L_world);
    c_friction [N m s/rad]: friction coefficient of the balances (0: plain conservation);
    p_psi: L_body[3] is conserved (symmetric about the pivot, centre of mass on e3);
    free: a free body (translation: E_total, |L|, L_world about the centre of mass and
    the momentum balance p(t) − p(t_from) − M g (t − t_from), docs/theory.md §7.1);
    note: printed above the drift table ('' when there is nothing to say); central: a free
    body in a central field (E_total with its potential, |L| and L_total about the central
    body, no momentum balance, docs/theory.md §9.7)."""

    t_from: float
    pivot: bool
    c_friction: float
    p_psi: bool
    note: str
    free: bool = False
    central: bool = False


def drift_plan(scene: Scene, stop_time: float) -> DriftPlan:
    """Which conserved quantities the scene has over [0, stop_time] s, from its data.

    After the input tables stop, the torques left are the scene's other features: none
    (``Scene.torque_free``: E_kin, |L| and L_world conserved, docs/theory.md §2.3), or
    gravity about the pivot, possibly with friction (E_total and p_phi, and p_psi for
    the Lagrange top, conserved or balanced by the friction integrals, §4.2, §4.3).
    Raises NotApplicable (with the reason) for a prescribed rate, inputs that never stop
    or outlast the horizon, and friction without gravity (no balance implemented)."""
    sc = scene
    if sc.has("prescribed_rate"):
        raise NotApplicable(
            "the rate is prescribed (features.prescribed_rate): w is held, not integrated, "
            "and the bearing torque changes L_world"
        )
    if sc.has("orbit") and not sc.torque_free:
        raise NotApplicable(
            "in an orbit with the gravity-gradient torque the conserved quantity is the Jacobi integral E_jacobi "
            "(docs/theory.md §9.3), which the orbit's own checks measure"
        )
    t_from = 0.0
    at_rest = not np.any(sc.w0 != 0.0) and not any(r.Omega0 != 0.0 for r in sc.rotors.values())
    if at_rest and not sc.inputs and not sc.moves and not sc.has("gravity"):
        raise NotApplicable("the body starts at rest with no input scheduled: nothing moves (E and L are 0)")
    if sc.inputs:
        t_free = _torque_free_from(sc)
        if t_free is None:
            raise NotApplicable("the inputs never stop: no torque-free tail to measure a drift over")
        if t_free >= stop_time:
            raise NotApplicable(f"the torque inputs act until t = {t_free:g} s, beyond the horizon {stop_time:g} s")
        t_from = t_free
    tail = dataclasses.replace(sc, features=sc.features - INPUT_FEATURES, inputs={}, force_points={})
    tail_note = f"torque-free tail t >= {t_from:g} s" if t_from > 0.0 else ""
    if tail.has("central_gravity") and tail.conserves_energy:  # E_total and L_total (§9.7)
        return DriftPlan(t_from, False, 0.0, False, tail_note, free=True, central=True)
    if sc.has("translation"):
        if not (tail.torque_free and tail.conserves_energy):
            raise NotApplicable(
                f"the free body keeps torques or forces after its inputs stop ({', '.join(sorted(tail.features))}): "
                "no conserved quantity implemented"
            )
        return DriftPlan(t_from, False, 0.0, False, tail_note, free=True)
    if tail.torque_free:
        return DriftPlan(t_from, False, 0.0, False, tail_note)
    if not tail.has("gravity"):
        raise NotApplicable(
            f"torques of {', '.join(sorted(tail.features))} without gravity: no conserved quantity or balance "
            "implemented (only the torque-free body and the top about a pivot, docs/theory.md §2.3, §4.2)"
        )
    # friction with c = 0 dissipates nothing: plain conservation, no balance terms
    c = 0.0 if tail.conserves_energy else float(sc.c_friction)
    I, r = np.asarray(sc.inertia, dtype=float), np.asarray(sc.r_cm, dtype=float)
    # I3 w3' = (I1 - I2) w1 w2 + (r_cm x weight) . e3 - c w3: p_psi = I3 w3 is conserved
    # (decays as e^{-c t/I3}) when I1 = I2 and r_cm is on e3 (docs/theory.md §4.2)
    p_psi = is_principal_diag(I) and I[0, 0] == I[1, 1] and r[0] == 0.0 and r[1] == 0.0
    notes = [tail_note] if tail_note else []
    if c != 0.0:
        notes.append("balances incl. friction")
    if not p_psi:
        notes.append("no p_psi: not a symmetric top with the centre of mass on e3")
    return DriftPlan(t_from, True, c, p_psi, "; ".join(notes))


def conserved_drifts(
    fmu_path: str | Path,
    scene: Scene | str | Path,
    methods: Sequence[str] = ("rk4", "gauss4", "splitting"),
    h_factors: Sequence[float] = (1.0, 10.0),
    stop_time: float | None = None,
    verbose: bool = False,
    scene_defaults: bool = False,
) -> list[DriftRow]:
    """Drift of the conserved quantities per FMU method and h_max = factor * scene h_max
    (methods not compiled into the FMU are skipped; the map name -> enumeration value is
    read from the modelDescription); scene_defaults: first a run with the scene's default
    method and settings (no start values; its row's method reads "<method> (defaults)").

    Free body (no torque): E_kin, |L|, L_world (vector, |L(t) - L(0)|/|L(0)|).
    Torque inputs: the same over the torque-free tail of the input tables.
    Free flight (translation): E_total (relative to the largest E_kin), |L|, L_world
    about the centre of mass, and p - M g t (relative to the largest |p|); in a central
    field E_total, |L| and L_total about the central body (docs/theory.md §9.7).
    Heavy top: E_total (relative to the kinetic energy scale), p_phi = L_world . e_up
    (e_up = -g/|g|; L_world[3] for g along -z) and p_psi = L_body[3] (both relative to
    |L|) — conserved (docs/theory.md §4.2). With friction the exact balances replace
    them: E_total + int c |w|^2 dt, p_phi + c int w_world . e_up dt (the weight's torque
    is horizontal) and p_psi(t) = p_psi(0) e^{-c t/I3} (I3 w3' = -c w3 for the symmetric
    top); integrals by cumulative Simpson (error O(H^4)). See :func:`drift_plan`; raises
    NotApplicable where the scene has no conserved quantity.
    """
    sc = load(scene)
    codes = method_codes(fmu_path)
    T = sc.stop_time if stop_time is None else float(stop_time)
    plan = drift_plan(sc, T)
    up = -np.asarray(sc.g, dtype=float) / float(np.linalg.norm(sc.g))
    rows = []
    runs = [(f"{sc.method} (defaults)", sc.h_max, {})] if scene_defaults else []
    runs += [
        (m, fac * sc.fixed_step, {"tolerance": 0.0, "h_max": fac * sc.fixed_step, "method": codes[m]})
        for m in methods
        if m in codes
        for fac in h_factors
    ]
    for mname, h, start in runs:
        t0 = time.perf_counter()
        r = run(fmu_path, sc, stop_time=T, start_values=start)
        wall = time.perf_counter() - t0
        k = r.time >= plan.t_from - 1e-12
        t = r.time[k]
        L = r.vector("L_total" if plan.central else "L_world")[k]
        Ln = np.linalg.norm(L, axis=1)
        d: dict[str, float] = {}
        if plan.free:
            E = r.values["E_total"][k]
            d["E_total"] = float(np.max(np.abs(E - E[0]))) / float(np.max(np.abs(r.values["E_kin"][k])))
            d["|L|"] = float(np.max(np.abs(Ln - Ln[0]))) / Ln[0]
            d["L_total" if plan.central else "L_world"] = float(np.max(np.linalg.norm(L - L[0], axis=1))) / Ln[0]
            if plan.central:  # the field pulls the centre of mass: p is not conserved
                rows.append(DriftRow(mname, h, d, wall))
                continue
            # p − M g t is constant (docs/theory.md §7.1); relative to the largest |p|
            g = np.asarray(sc.g, dtype=float) if sc.has("gravity") else np.zeros(3)
            pb = r.vector("p")[k] - float(sc.mass) * np.outer(t - t[0], g)
            pscale = float(np.max(np.linalg.norm(r.vector("p")[k], axis=1)))
            d["p - M g t"] = float(np.max(np.linalg.norm(pb - pb[0], axis=1))) / pscale
        elif plan.pivot:
            E = r.values["E_total"][k]
            Escale = float(np.max(np.abs(r.values["E_kin"][k])))
            pphi, ppsi = L @ up, r.vector("L_body")[k, 2]
            c = plan.c_friction
            if c != 0.0:
                w = r.vector("w_body")[k]
                E = E + c * cumulative_simpson(np.sum(w * w, axis=1), x=t, initial=0.0)
                pphi = pphi + c * cumulative_simpson(r.vector("w_world")[k] @ up, x=t, initial=0.0)
                ppsi = ppsi - ppsi[0] * np.exp(-c * (t - t[0]) / float(sc.inertia[2, 2])) + ppsi[0]
            d["E_total"] = float(np.max(np.abs(E - E[0]))) / Escale
            d["p_phi"] = float(np.max(np.abs(pphi - pphi[0]))) / Ln[0]
            if plan.p_psi:
                d["p_psi"] = float(np.max(np.abs(ppsi - ppsi[0]))) / Ln[0]
        else:
            E = r.values["E_kin"][k]
            d["E_kin"] = float(np.max(np.abs(E - E[0]))) / E[0]
            d["|L|"] = float(np.max(np.abs(Ln - Ln[0]))) / Ln[0]
            d["L_world"] = float(np.max(np.linalg.norm(L - L[0], axis=1))) / Ln[0]
        rows.append(DriftRow(mname, h, d, wall))
    if verbose:
        for row in rows:
            txt = ", ".join(f"{k} {v:.1e}" for k, v in row.drifts.items())
            print(f"  {sc.name} {row.method:9s} h_max {row.h_max:.0e}: {txt} ({row.wall_time:.2f} s)")
    return rows
