r"""Independent cross-check of the shipped scenes: FMU vs Exudyn vs closed forms.

Every check drives a scene's FMU through fmpy (:mod:`fmu.run`), runs the same scene in
Exudyn (:mod:`rbcheck.exudyn_models`, its own equations and integrators) and compares
both with the closed forms of :mod:`rbcheck.free_symmetric`, :mod:`rbcheck.free_asymmetric`
and :mod:`rbcheck.heavy_top`. Of the project this module imports only the FMU driver
(``fmu.run``, ``fmu.build_fmu``) and the scene reader (``modelsrc.scene``, read as data);
no physics of ``modelsrc`` is used. Quantities are measured from the sampled
trajectories with :mod:`rbcheck.motion_fits`.

Units SI; ``w`` = body angular velocity [rad/s]; ``q`` = unit quaternion (w, x, y, z)
body -> world; for the tops the world z axis points up, ``theta`` is the tilt of the
figure axis e3 from it and ``u = cos(theta) = R33``.

Checks (docs/theory.md §2.3, §4.2; the numbers are returned, ``main`` prints them):

1. :func:`tennis_racket` — growth rate of a small perturbation of a spin about the
   intermediate axis against ``tennis_racket_exponent``; boundedness about the other
   two axes against the exact invariant ``L^2 - 2 E I_k``.
2. :func:`symmetric_top_rates` — body precession rate Omega and coning rate |L|/I1.
3. :func:`heavy_top_nutation` — nutation bounds u1, u2, nutation period, mean
   precession against the elliptic closed form (I1 about the PIVOT).
4. :func:`fast_top_scaling` — the fast-top approximations over a ladder of spins.
5. :func:`sleeping_threshold` and :func:`friction_onset` — the sleeping-top threshold.
6. :func:`fmu_vs_exudyn` and :func:`conserved_drifts` — trajectories and invariants.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import tempfile
import time as _time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from fmpy import read_model_description
from scipy.integrate import cumulative_simpson

from . import free_asymmetric, free_symmetric
from . import heavy_top as ht
from . import motion_fits as mf
from .exudyn_models import simulate_scene
from .rotation_np import quat_to_matrix, rotation_angle_between

__all__ = [
    "SCENES",
    "method_codes",
    "top_params",
    "tennis_racket_exponent",
    "TennisRacketResult",
    "tennis_racket",
    "SymmetricTopResult",
    "symmetric_top_rates",
    "NutationMeasurement",
    "measure_nutation",
    "HeavyTopResult",
    "heavy_top_nutation",
    "FastTopRow",
    "FastTopResult",
    "fast_top_scaling",
    "growth_rate_vertical",
    "SleepingResult",
    "sleeping_threshold",
    "VerticalGrowthResult",
    "vertical_growth",
    "OnsetResult",
    "friction_onset",
    "TrajectoryComparison",
    "fmu_vs_exudyn",
    "DriftRow",
    "conserved_drifts",
    "Row",
    "SceneReport",
    "scene_report",
    "format_report",
    "main",
]

SCENES = (
    "free_asymmetric",
    "symmetric_free",
    "heavy_top",
    "sleeping_top",
    "torque_driven",
    "skewed_bar",
    "two_frame_arm",
)


# ----------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------
def _load(scene_or_name: Any):
    from modelsrc.scene import load_scene  # scene files are data; no physics imported

    return load_scene(scene_or_name) if isinstance(scene_or_name, (str, Path)) else scene_or_name


def _run(fmu_path: str | Path, scene: Any, **kw: Any):
    from fmu.run import run_fmu

    return run_fmu(fmu_path, scene, **kw)


def method_codes(fmu_path: str | Path) -> dict[str, int]:
    """Integrator name -> value of the FMU's ``method`` enumeration, read from its
    modelDescription.xml (so the check does not depend on ``modelsrc``)."""
    md = read_model_description(str(fmu_path))
    for td in md.typeDefinitions:
        if td.type == "Enumeration" and td.name == "Method":
            return {it.name: int(it.value) for it in td.items}
    raise ValueError(f"{fmu_path}: the FMU has no 'Method' enumeration type")


def _start(w: ArrayLike | None = None, q: ArrayLike | None = None, **extra: float) -> dict[str, float]:
    sv: dict[str, float] = {}
    if w is not None:
        sv.update({f"w_body[{k + 1}]": float(x) for k, x in enumerate(np.asarray(w, dtype=float))})
    if q is not None:
        sv.update({f"q[{k + 1}]": float(x) for k, x in enumerate(np.asarray(q, dtype=float))})
    sv.update({k: float(v) for k, v in extra.items()})
    return sv


def _exudyn(
    scene: Any,
    w: ArrayLike | None = None,
    q: ArrayLike | None = None,
    stop_time: float | None = None,
    step: float | None = None,
    h: float | None = None,
    solver: str = "RK67",
) -> dict[str, Any]:
    """Exudyn run of the scene with another start state (the scene is copied, not changed)."""
    changes: dict[str, Any] = {}
    if w is not None:
        changes["w0"] = np.asarray(w, dtype=float)
    if q is not None:
        changes["q0"] = np.asarray(q, dtype=float)
    if stop_time is not None:
        changes["stop_time"] = float(stop_time)
    if step is not None:
        changes["step"] = float(step)
    sc = dataclasses.replace(scene, **changes) if changes else scene
    return simulate_scene(sc, solver=solver, h=h)


def _is_principal_diag(I: NDArray) -> bool:
    return bool(np.all(I[~np.eye(3, dtype=bool)] == 0.0))


def top_params(scene: Any) -> ht.TopParams:
    """Lagrange-top parameters of a gravity scene. I1 is the transverse moment about the
    PIVOT, ``I1 = I1_cm + M l^2`` (parallel-axis theorem, docs/theory.md §3.2), since the
    closed form (Korean notes ⊕) is written about the fixed point.

    Requires a symmetric top: diagonal inertia with I11 = I22, r_cm = l e3 (l > 0) and
    g = -g e_z; raises ValueError naming the offending value otherwise."""
    I = np.asarray(scene.inertia, dtype=float)
    r = np.asarray(scene.r_cm, dtype=float)
    g = np.asarray(scene.g, dtype=float)
    if not _is_principal_diag(I) or I[0, 0] != I[1, 1]:
        raise ValueError(
            f"scene {scene.name}: the heavy-top closed form needs diag(I1, I1, I3), got inertia {I.tolist()}"
        )
    if r[0] != 0.0 or r[1] != 0.0 or not r[2] > 0.0:
        raise ValueError(f"scene {scene.name}: r_cm must be (0, 0, l) with l > 0, got {r.tolist()}")
    if g[0] != 0.0 or g[1] != 0.0 or not g[2] < 0.0:
        raise ValueError(f"scene {scene.name}: g must be (0, 0, -g) with g > 0, got {g.tolist()}")
    M, l = float(scene.mass), float(r[2])
    return ht.TopParams(I1=float(I[0, 0]) + M * l * l, I3=float(I[2, 2]), M=M, g=float(-g[2]), l=l)


def _tilted_quaternion(theta: float) -> NDArray[np.float64]:
    """Rotation by theta [rad] about world x: figure axis tilted theta from z (phi = psi = 0)."""
    return np.array([math.cos(0.5 * theta), math.sin(0.5 * theta), 0.0, 0.0])


# ----------------------------------------------------------------------------------
# 1. tennis racket
# ----------------------------------------------------------------------------------
def tennis_racket_exponent(I_principal: ArrayLike, axis: int, spin: float) -> float:
    r"""``lambda^2`` [1/s^2] of a small perturbation of a steady spin ``spin`` [rad/s]
    about principal axis ``axis`` (0, 1 or 2) of ``diag(I1, I2, I3)`` [kg m^2].

    Linearising Euler's equations about ``w = spin e_k`` (k = axis, i, j the other two):
    ``I_i dw_i' = (I_j - I_k) spin dw_j`` and ``I_j dw_j' = (I_k - I_i) spin dw_i``, so
    ``dw_i'' = lambda^2 dw_i`` with

        lambda^2 = spin^2 (I_k - I_i)(I_j - I_k) / (I_i I_j).

    For k = 1 this is the notes' ``w1^2 (I1 - I2)(I3 - I1)/(I2 I3)`` (docs/theory.md §2.3);
    for the intermediate axis k = 2 of I = diag(1, 2, 3) the indices rotate to
    ``w2^2 (I2 - I1)(I3 - I2)/(I1 I3) = w2^2/3``. Positive (exponential growth) iff I_k
    is the intermediate moment; negative values are ``-(oscillation frequency)^2``.
    """
    I = np.asarray(I_principal, dtype=float).reshape(3)
    if axis not in (0, 1, 2):
        raise ValueError(f"axis must be 0, 1 or 2, got {axis!r}")
    if not np.all(I > 0):
        raise ValueError(f"principal moments must be > 0, got {I.tolist()}")
    i, j = [a for a in range(3) if a != axis]
    k = axis
    return float(spin) ** 2 * (I[k] - I[i]) * (I[j] - I[k]) / (I[i] * I[j])


def _perturbation_bound(I: NDArray, axis: int, w0: NDArray) -> float:
    """Exact bound on |dw(t)| = |w(t) minus its axis component| for a spin about an
    EXTREME axis k: ``Q = L^2 - 2 E I_k = sum_i I_i (I_i - I_k) w_i^2`` is conserved
    (L^2 and E are), and its weights ``I_i |I_i - I_k|`` (i != k) have one sign, so
    ``|dw|^2 <= |Q| / min_i I_i |I_i - I_k|``."""
    wts = np.array([I[i] * (I[i] - I[axis]) for i in range(3) if i != axis])
    if not (np.all(wts > 0) or np.all(wts < 0)):
        raise ValueError(f"axis {axis} is the intermediate axis of {I.tolist()}: no bound")
    d = np.delete(w0, axis)
    Q = float(np.sum(wts * d * d))
    return math.sqrt(abs(Q) / float(np.min(np.abs(wts))))


@dataclass
class TennisRacketResult:
    """Tennis-racket check. lam_formula [1/s] from ``tennis_racket_exponent`` for the
    intermediate axis; fit_fmu/fit_exudyn: ``GrowthFit`` of |dw| (the body components
    off the spin axis); rel_err_* = fit/formula - 1. growth_*[axis] = max_t |dw(t)|/|dw(0)|
    for spins about each axis, bound[axis] = the exact invariant bound of that ratio
    (extreme axes only; nan for the intermediate one)."""

    I: tuple[float, float, float]
    spin: float
    delta: float
    intermediate_axis: int
    lam_formula: float
    fit_fmu: mf.GrowthFit
    fit_exudyn: mf.GrowthFit | None
    rel_err_fmu: float
    rel_err_exudyn: float
    growth_fmu: dict[int, float] = field(default_factory=dict)
    growth_exudyn: dict[int, float] = field(default_factory=dict)
    bound: dict[int, float] = field(default_factory=dict)
    stop_time: float = 0.0
    wall_time: float = 0.0


def tennis_racket(
    fmu_path: str | Path,
    scene: Any = "free_asymmetric",
    spin: float = 1.0,
    delta: float = 1e-6,
    exudyn: bool = True,
    verbose: bool = False,
) -> TennisRacketResult:
    """Spin ``spin`` [rad/s] about each principal axis of a torque-free scene with
    ``delta`` [rad/s] added to both other body components; fit the growth rate for the
    intermediate axis and the growth ratio for all three.

    Fit window: |dw| from 100 |dw0| to 1e4 |dw0|. With dw = A e^{lam t} + B e^{-lam t},
    |A|, |B| <~ |dw0|, the decaying mode is below (|dw0|/(100 |dw0|))^2 = 1e-4 of the
    growing one at the window start; at the end the spin component has changed by
    ~|dw|^2/(2 spin^2) <~ 1e-4 (delta = 1e-6), so the fitted rate is biased by < 1e-4.
    """
    t0 = _time.perf_counter()
    sc = _load(scene)
    I = np.asarray(sc.inertia, dtype=float)
    if sc.features or not _is_principal_diag(I):
        raise ValueError(
            f"scene {sc.name}: tennis_racket needs a torque-free body in principal "
            f"axes, got features {sorted(sc.features)} and inertia {I.tolist()}"
        )
    Id = np.diag(I).copy()
    order = np.argsort(Id)
    if len(set(Id.tolist())) != 3:
        raise ValueError(f"scene {sc.name}: principal moments must be distinct, got {Id.tolist()}")
    k_mid = int(order[1])
    lam = math.sqrt(tennis_racket_exponent(Id, k_mid, spin))
    d0 = math.sqrt(2.0) * delta
    lo, hi = 100.0 * d0, 1e4 * d0
    # time to reach hi: |A| >= |dw0|/2 (A = (dw0 + dw0'/lam)/2 componentwise), plus 2/lam margin
    T = (math.log(hi / (0.5 * d0)) + 2.0) / lam
    H = min(sc.step, 0.02 / lam)  # >= 50 samples per e-folding
    growth_f: dict[int, float] = {}
    growth_e: dict[int, float] = {}
    bound: dict[int, float] = {}
    fit_f: mf.GrowthFit | None = None
    fit_e: mf.GrowthFit | None = None
    for k in range(3):
        w0 = np.full(3, delta)
        w0[k] = spin
        r = _run(
            fmu_path,
            sc,
            stop_time=T,
            step=H,
            start_values=_start(w0, [1, 0, 0, 0]),
            outputs=[f"w_body[{i}]" for i in (1, 2, 3)],
        )
        dw = np.linalg.norm(np.delete(r.vector("w_body"), k, axis=1), axis=1)
        growth_f[k] = float(np.max(dw) / dw[0])
        e = _exudyn(sc, w=w0, q=[1, 0, 0, 0], stop_time=T, step=H) if exudyn else None
        if e is not None:
            dwe = np.linalg.norm(np.delete(e["w_body"], k, axis=1), axis=1)
            growth_e[k] = float(np.max(dwe) / dwe[0])
        if k == k_mid:
            bound[k] = float("nan")
            fit_f = mf.fit_exponential_growth(r.time, dw, lo, hi)
            if e is not None:
                fit_e = mf.fit_exponential_growth(e["time"], dwe, lo, hi)
        else:
            bound[k] = _perturbation_bound(Id, k, w0) / d0
    assert fit_f is not None
    res = TennisRacketResult(
        I=(float(Id[0]), float(Id[1]), float(Id[2])),
        spin=spin,
        delta=delta,
        intermediate_axis=k_mid,
        lam_formula=lam,
        fit_fmu=fit_f,
        fit_exudyn=fit_e,
        rel_err_fmu=fit_f.rate / lam - 1.0,
        rel_err_exudyn=fit_e.rate / lam - 1.0 if fit_e is not None else float("nan"),
        growth_fmu=growth_f,
        growth_exudyn=growth_e,
        bound=bound,
        stop_time=T,
    )
    res.wall_time = _time.perf_counter() - t0
    if verbose:
        print(
            f"tennis racket I={Id.tolist()} spin {spin} rad/s about axis {k_mid + 1}, "
            f"delta {delta:g}: lambda formula {lam:.9f} 1/s"
        )
        print(
            f"  FMU fit {res.fit_fmu.rate:.9f} (rel err {res.rel_err_fmu:+.2e}) over "
            f"[{res.fit_fmu.t_start:.2f}, {res.fit_fmu.t_end:.2f}] s"
        )
        if res.fit_exudyn is not None:
            print(f"  Exudyn fit {res.fit_exudyn.rate:.9f} (rel err {res.rel_err_exudyn:+.2e})")
        for k in range(3):
            print(
                f"  spin about axis {k + 1}: max|dw|/|dw0| FMU {res.growth_fmu[k]:.10g}, Exudyn "
                f"{res.growth_exudyn.get(k, float('nan')):.10g}, invariant bound {res.bound[k]:.10g}"
            )
    return res


# ----------------------------------------------------------------------------------
# 2. torque-free symmetric top
# ----------------------------------------------------------------------------------
@dataclass
class SymmetricTopResult:
    """Rates [rad/s] of the torque-free symmetric top: Omega (w1 + i w2 turns as
    e^{-i Omega t} in the body, Marin "Example: Symmetric top") and the coning rate of
    the figure axis about L_world; *_formula from the initial data, *_fmu / *_exudyn
    measured by least-squares phase slopes."""

    omega_formula: float
    omega_fmu: float
    omega_exudyn: float
    coning_formula: float
    coning_fmu: float
    coning_exudyn: float
    stop_time: float
    wall_time: float


def symmetric_top_rates(
    fmu_path: str | Path,
    scene: Any = "symmetric_free",
    stop_time: float | None = None,
    exudyn: bool = True,
    verbose: bool = False,
) -> SymmetricTopResult:
    """Measure Omega = w3 (I1 - I3)/I1 and |L|/I1 from the FMU (and Exudyn)."""
    t0 = _time.perf_counter()
    sc = _load(scene)
    I = np.asarray(sc.inertia, dtype=float)
    if sc.features or not _is_principal_diag(I) or I[0, 0] != I[1, 1]:
        raise ValueError(
            f"scene {sc.name}: needs a torque-free body diag(I1, I1, I3), got "
            f"features {sorted(sc.features)}, inertia {I.tolist()}"
        )
    I1, I3 = float(I[0, 0]), float(I[2, 2])
    w0 = np.asarray(sc.w0, dtype=float)
    om_f = free_symmetric.precession_rate(I1, I3, w0[2])
    L0 = quat_to_matrix(sc.q0) @ (I @ w0)
    con_f = free_symmetric.body_precession_about_L(I1, L0)
    T = sc.stop_time if stop_time is None else float(stop_time)

    def measure(t, w, q, L):
        # w1 + i w2 = c e^{-i Omega t}  =>  Omega = -d arg(w1 + i w2)/dt
        om = -mf.phase_rate(t, w[:, 0] + 1j * w[:, 1])
        con = mf.rotation_rate_about(t, mf.figure_axis_world(q), L[0])
        return om, con

    r = _run(fmu_path, sc, stop_time=T)
    om_m, con_m = measure(r.time, r.vector("w_body"), r.vector("q"), r.vector("L_world"))
    om_e = con_e = float("nan")
    if exudyn:
        e = _exudyn(sc, stop_time=T)
        om_e, con_e = measure(e["time"], e["w_body"], e["q"], e["L_world"])
    out = SymmetricTopResult(om_f, om_m, om_e, con_f, con_m, con_e, T, _time.perf_counter() - t0)
    if verbose:
        print(
            f"symmetric top: Omega formula {om_f:.12f}, FMU {om_m:.12f} ({om_m / om_f - 1:+.1e}), "
            f"Exudyn {om_e:.12f} ({om_e / om_f - 1:+.1e}) rad/s"
        )
        print(
            f"  coning |L|/I1 formula {con_f:.12f}, FMU {con_m:.12f} ({con_m / con_f - 1:+.1e}), "
            f"Exudyn {con_e:.12f} ({con_e / con_f - 1:+.1e}) rad/s"
        )
    return out


# ----------------------------------------------------------------------------------
# 3. heavy top nutation
# ----------------------------------------------------------------------------------
@dataclass
class NutationMeasurement:
    """Nutation measured from a sampled top trajectory: u_min/u_max = refined local
    minima/maxima of u = cos(theta) (one per nutation period), period [s] = mean spacing
    of the upward crossings of the mid level (u_min + u_max)/2, precession [rad/s] = mean
    phi rate between the first and last such crossing (whole periods), n_periods."""

    u_min: NDArray[np.float64]
    u_max: NDArray[np.float64]
    period: float
    precession: float
    n_periods: int

    @property
    def u1(self) -> float:
        """Mean of the nutation minima of u (the lower bound u1)."""
        return float(np.mean(self.u_min))

    @property
    def u2(self) -> float:
        """Mean of the nutation maxima of u (the upper bound u2)."""
        return float(np.mean(self.u_max))

    @property
    def amplitude(self) -> float:
        """u2 - u1."""
        return self.u2 - self.u1


def measure_nutation(t: ArrayLike, q: ArrayLike) -> NutationMeasurement:
    """Nutation bounds, period and mean precession of a top from times t [s] and
    quaternions q (n, 4); needs at least two full nutation periods."""
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    u = mf.cos_tilt(q)
    _, umin = mf.refined_extrema(t, u, "min")
    _, umax = mf.refined_extrema(t, u, "max")
    if umin.size < 2 or umax.size < 1:
        raise ValueError(
            f"measure_nutation: found {umin.size} minima and {umax.size} maxima of "
            f"cos(theta) in [{t[0]}, {t[-1]}] s; run at least two nutation periods"
        )
    mid = 0.5 * (float(np.mean(umin)) + float(np.mean(umax)))
    tc = mf.crossing_times(t, u, mid, +1)
    if tc.size < 2:
        raise ValueError(f"measure_nutation: {tc.size} upward crossings of u = {mid}; run longer")
    phi = mf.precession_angle(q)
    ph = mf.interp_cubic(t, phi, tc[[0, -1]])
    prec = float((ph[1] - ph[0]) / (tc[-1] - tc[0]))
    return NutationMeasurement(umin, umax, mf.mean_period(tc), prec, int(tc.size - 1))


def _closed_precession(top: ht.HeavyTop) -> float:
    """Exact mean precession rate [rad/s]: phi advance over one nutation period / period."""
    _, phi, _ = top.angles(np.array([top.period]))
    return float((phi[0] - top.init.phi0) / top.period)


@dataclass
class HeavyTopResult:
    """Heavy-top nutation: closed form (u1, u2 [-], period [s], precession [rad/s]) and
    the FMU / Exudyn measurements; max_du_* = max_t |u(t) - u_closed(t)|."""

    w3: float
    u1: float
    u2: float
    period: float
    precession: float
    fmu: NutationMeasurement
    exudyn: NutationMeasurement | None
    max_du_fmu: float
    max_du_exudyn: float
    stop_time: float
    step: float
    h_max: float
    wall_time: float


def heavy_top_nutation(
    fmu_path: str | Path,
    scene: Any = "heavy_top",
    w3: float | None = None,
    periods: float = 8.2,
    step: float | None = None,
    h_max: float | None = None,
    exudyn: bool = True,
    verbose: bool = False,
) -> HeavyTopResult:
    """Run the top from the scene's start attitude with body spin (0, 0, w3) (default the
    scene's) for ``periods`` closed-form nutation periods and compare the nutation with
    :class:`rbcheck.heavy_top.HeavyTop`. Default step: the scene's, h_max: the scene's."""
    t0 = _time.perf_counter()
    sc = _load(scene)
    P = top_params(sc)
    w = np.asarray(sc.w0, dtype=float).copy()
    if w3 is not None:
        w = np.array([0.0, 0.0, float(w3)])
    top = ht.HeavyTop(P, ht.init_from_state(sc.q0, w))
    if not np.isfinite(top.period):
        raise ValueError(f"scene {sc.name} with w = {w.tolist()}: steady motion, no nutation")
    T = periods * top.period
    H = sc.step if step is None else float(step)
    h = sc.h_max if h_max is None else float(h_max)
    r = _run(
        fmu_path,
        sc,
        stop_time=T,
        step=H,
        start_values=_start(w, sc.q0, h_max=h),
        outputs=[f"q[{i}]" for i in (1, 2, 3, 4)],
    )
    q = r.vector("q")
    m_f = measure_nutation(r.time, q)
    du_f = float(np.max(np.abs(mf.cos_tilt(q) - top.u(r.time))))
    m_e, du_e = None, float("nan")
    if exudyn:
        e = _exudyn(sc, w=w, stop_time=T, step=H, h=h)
        m_e = measure_nutation(e["time"], e["q"])
        du_e = float(np.max(np.abs(mf.cos_tilt(e["q"]) - top.u(e["time"]))))
    out = HeavyTopResult(
        float(w[2]),
        top.u1,
        top.u2,
        top.period,
        _closed_precession(top),
        m_f,
        m_e,
        du_f,
        du_e,
        T,
        H,
        h,
        _time.perf_counter() - t0,
    )
    if verbose:
        print(f"heavy top w3 = {w[2]:g} rad/s (I1 about pivot {P.I1:.6e} kg m^2), {m_f.n_periods} periods:")
        for lab, m in (("FMU", m_f), ("Exudyn", m_e)):
            if m is None:
                continue
            print(
                f"  {lab:6s} u1 {m.u1:.12f} (worst {np.max(np.abs(m.u_min - top.u1)):.1e}), "
                f"u2 {m.u2:.12f} (worst {np.max(np.abs(m.u_max - top.u2)):.1e}), period "
                f"{m.period:.10f} s ({m.period / top.period - 1:+.1e}), precession "
                f"{m.precession:.9f} rad/s ({m.precession / out.precession - 1:+.1e})"
            )
        print(
            f"  closed u1 {top.u1:.12f}, u2 {top.u2:.12f}, period {top.period:.10f} s, precession "
            f"{out.precession:.9f} rad/s; max|u - u_closed| FMU {du_f:.1e}, Exudyn {du_e:.1e}"
        )
    return out


# ----------------------------------------------------------------------------------
# 4. fast top
# ----------------------------------------------------------------------------------
@dataclass
class FastTopRow:
    """One spin w3 [rad/s] of the fast-top ladder: amplitude u2 - u1 [-], nutation
    frequency [rad/s] and mean precession [rad/s], each measured from the FMU, exact
    (closed form) and fast-top approximation (docs/theory.md §4.2, Korean notes ⊕(5));
    sigma = (w_c/w3)^2 with w_c the sleeping threshold (the expansion parameter)."""

    w3: float
    sigma: float
    amp_fmu: float
    amp_closed: float
    amp_approx: float
    freq_fmu: float
    freq_closed: float
    freq_approx: float
    prec_fmu: float
    prec_closed: float
    prec_approx: float

    def approx_error(self, which: str) -> float:
        """Relative error of the approximation vs the FMU measurement (approx/FMU - 1)."""
        a, m = {
            "amp": (self.amp_approx, self.amp_fmu),
            "freq": (self.freq_approx, self.freq_fmu),
            "prec": (self.prec_approx, self.prec_fmu),
        }[which]
        return a / m - 1.0


@dataclass
class FastTopResult:
    """Fast-top ladder: rows, log-log slope of the FMU amplitude over all spins and over
    the asymptotic spins (sigma <= sigma_max), u0 = cos(theta0)."""

    rows: list[FastTopRow]
    slope_all: float
    slope_asymptotic: float
    asymptotic_w3: tuple[float, ...]
    sigma_max: float
    u0: float
    wall_time: float

    @property
    def slope_bias_bound(self) -> float:
        """First-order bound on |slope_asymptotic + 2|. The exact amplitude is
        ``(beta/a^2) sin^2(theta0) (1 + u0 sigma + O(sigma^2))`` (expanding the root of
        ``f(u) = (u0 - u)[beta (1 - u^2) - a^2 (u0 - u)]`` for theta0' = phi0' = 0), so
        ln(amplitude) = const - 2 ln w3 + ln(1 + u0 sigma), and the last term, between 0
        and u0 sigma_min, tilts the fitted slope by at most u0 sigma_min / ln(w_max/w_min)
        (exact for two or three log-equispaced spins)."""
        w = np.asarray(self.asymptotic_w3, dtype=float)
        if w.size < 2:
            return float("nan")
        sig = max(r.sigma for r in self.rows if r.w3 in self.asymptotic_w3)  # at w_min
        return float(self.u0 * sig / math.log(w.max() / w.min()))


def fast_top_scaling(
    fmu_path: str | Path,
    scene: Any = "heavy_top",
    w3_values: Sequence[float] = (150.0, 300.0, 600.0, 1200.0, 2400.0),
    periods: float = 6.2,
    h_omega: float = 0.015,
    samples_per_period: int = 400,
    sigma_max: float = 0.05,
    verbose: bool = False,
) -> FastTopResult:
    """Spin the scene's top at each w3 from its start attitude (theta0' = phi0' = 0) and
    measure the nutation. RK4 step h_max = h_omega/w3 (same accuracy per spin period at
    every w3), communication step = period/samples_per_period."""
    t0 = _time.perf_counter()
    sc = _load(scene)
    P = top_params(sc)
    wc = ht.sleeping_threshold(P.I1, P.I3, P.M, P.g, P.l)
    rows = []
    u0 = theta0 = float("nan")
    for w3 in w3_values:
        w = np.array([0.0, 0.0, float(w3)])
        init = ht.init_from_state(sc.q0, w)
        if init.theta_dot0 != 0.0 or init.phi_dot0 != 0.0:
            raise ValueError(f"scene {sc.name}: fast-top formulas need theta0' = phi0' = 0")
        theta0, u0 = init.theta0, math.cos(init.theta0)
        top = ht.HeavyTop(P, init)
        T = periods * top.period
        H = top.period / samples_per_period
        r = _run(
            fmu_path,
            sc,
            stop_time=T,
            step=H,
            start_values=_start(w, sc.q0, h_max=h_omega / w3),
            outputs=[f"q[{i}]" for i in (1, 2, 3, 4)],
        )
        m = measure_nutation(r.time, r.vector("q"))
        rows.append(
            FastTopRow(
                w3=float(w3),
                sigma=(wc / w3) ** 2,
                amp_fmu=m.amplitude,
                amp_closed=top.u2 - top.u1,
                amp_approx=ht.fast_top_nutation_amplitude(P.I1, P.I3, P.M, P.g, P.l, w3, theta0),
                freq_fmu=2 * math.pi / m.period,
                freq_closed=2 * math.pi / top.period,
                freq_approx=ht.fast_top_nutation_frequency(P.I1, P.I3, w3),
                prec_fmu=m.precession,
                prec_closed=_closed_precession(top),
                prec_approx=ht.fast_top_precession_rate(P.I3, P.M, P.g, P.l, w3),
            )
        )
    ws = np.array([r.w3 for r in rows])
    amps = np.array([r.amp_fmu for r in rows])
    asym = np.array([r.sigma <= sigma_max for r in rows])
    slope_all = mf.loglog_slope(ws, amps)
    slope_asym = mf.loglog_slope(ws[asym], amps[asym]) if asym.sum() >= 2 else float("nan")
    out = FastTopResult(rows, slope_all, slope_asym, tuple(ws[asym].tolist()), sigma_max, u0, _time.perf_counter() - t0)
    if verbose:
        print(f"fast top (theta0 = {theta0:.3f} rad, w_c = {wc:.3f} rad/s): rel. error = approx/FMU - 1")
        print(
            "     w3  sigma    amp FMU      amp/closed-1  amp err   freq FMU   freq/cl-1  freq err"
            "  prec FMU   prec/cl-1  prec err"
        )
        for r in rows:
            print(
                f"  {r.w3:5.0f} {r.sigma:6.4f} {r.amp_fmu:.6e} {r.amp_fmu / r.amp_closed - 1:+.1e} "
                f"{r.approx_error('amp'):+.2e} {r.freq_fmu:9.4f} {r.freq_fmu / r.freq_closed - 1:+.1e} "
                f"{r.approx_error('freq'):+.2e} {r.prec_fmu:8.5f} {r.prec_fmu / r.prec_closed - 1:+.1e} "
                f"{r.approx_error('prec'):+.2e}"
            )
        print(
            f"  log-log slope of the amplitude: all spins {slope_all:.4f}; sigma <= {sigma_max} "
            f"(w3 = {out.asymptotic_w3}) {slope_asym:.4f}"
        )
    return out


# ----------------------------------------------------------------------------------
# 5. sleeping top
# ----------------------------------------------------------------------------------
def growth_rate_vertical(P: ht.TopParams, w3: ArrayLike) -> NDArray[np.float64]:
    r"""Growth rate [1/s] of a small tilt of the upright top spinning at w3 [rad/s].

    Linearised about the vertical with the complex tilt xi = theta e^{i phi} (e3_world ~
    (xi_x, xi_y, 1)): ``I1 xi'' - i I3 w3 xi' - M g l xi = 0`` (I1 about the pivot), so
    xi ~ e^{s t} with ``s = [i I3 w3 +- sqrt(4 M g l I1 - I3^2 w3^2)] / (2 I1)`` and

        lambda^2 = (4 M g l I1 - I3^2 w3^2) / (4 I1^2),

    positive below the threshold w3^2 = 4 M g l I1/I3^2 (docs/theory.md §4.2); 0 above it.
    """
    w3 = np.asarray(w3, dtype=float)
    lam2 = (4.0 * P.M * P.g * P.l * P.I1 - (P.I3 * w3) ** 2) / (4.0 * P.I1**2)
    return np.sqrt(np.maximum(lam2, 0.0))


@dataclass
class SleepingResult:
    """Upright start (tilt theta0 [rad], no transverse rate) at w3 = factor * w_c:
    max tilt [rad] from the FMU / Exudyn / closed form (u1 of the elliptic solution)
    over stop_time [s]; period = closed-form nutation period [s] (the tilt beat);
    lam = growth_rate_vertical at w3 [1/s] (0 above threshold)."""

    factor: float
    w3: float
    w_c: float
    theta0: float
    max_tilt_fmu: float
    max_tilt_exudyn: float
    max_tilt_closed: float
    period: float
    lam: float
    stop_time: float
    wall_time: float


def _frictionless(sc: Any) -> tuple[Any, dict[str, float]]:
    """The scene without friction (for the frictionless closed forms) and the FMU start
    values that switch its friction off (c_friction = 0; empty for a frictionless scene)."""
    if not sc.has("friction"):
        return sc, {}
    return dataclasses.replace(sc, features=sc.features - {"friction"}, c_friction=0.0), {"c_friction": 0.0}


def sleeping_threshold(
    fmu_path: str | Path,
    scene: Any = "heavy_top",
    factor: float = 1.02,
    theta0: float = 1e-3,
    periods: float = 10.0,
    step: float | None = None,
    exudyn: bool = True,
    verbose: bool = False,
) -> SleepingResult:
    """Start the top ``theta0`` from upright with body spin (0, 0, factor * w_c) and no
    transverse rate; run ``periods`` closed-form nutation periods and return the largest
    tilt. A friction scene is run frictionless (FMU parameter ``c_friction`` = 0, Exudyn
    scene copy without the friction feature), as the closed form has no friction."""
    t0 = _time.perf_counter()
    sc, extra = _frictionless(_load(scene))
    P = top_params(sc)
    wc = ht.sleeping_threshold(P.I1, P.I3, P.M, P.g, P.l)
    w = np.array([0.0, 0.0, factor * wc])
    q0 = _tilted_quaternion(theta0)
    top = ht.HeavyTop(P, ht.TopInit(theta0, 0.0, 0.0, 0.0, 0.0, w[2]))
    th_max = 2.0 * math.atan2(math.sqrt(top.omu1), math.sqrt(top.opu1))  # u1 -> largest tilt
    T = periods * top.period
    H = sc.step if step is None else float(step)
    r = _run(
        fmu_path,
        sc,
        stop_time=T,
        step=H,
        start_values=_start(w, q0, **extra),
        outputs=[f"q[{i}]" for i in (1, 2, 3, 4)],
    )

    def max_tilt(t, q):
        tilt = mf.tilt_angle(q)
        _, vals = mf.refined_extrema(t, tilt, "max")
        return float(max(np.max(tilt), np.max(vals) if vals.size else -np.inf))

    mt_f = max_tilt(r.time, r.vector("q"))
    mt_e = float("nan")
    if exudyn:
        e = _exudyn(sc, w=w, q=q0, stop_time=T, step=H)
        mt_e = max_tilt(e["time"], e["q"])
    out = SleepingResult(
        factor,
        float(w[2]),
        wc,
        theta0,
        mt_f,
        mt_e,
        th_max,
        top.period,
        float(growth_rate_vertical(P, w[2])),
        T,
        _time.perf_counter() - t0,
    )
    if verbose:
        print(
            f"sleeping top w3 = {factor:.2f} w_c = {w[2]:.4f} rad/s, tilt0 {theta0:g} rad, "
            f"{periods:g} periods = {T:.2f} s: max tilt FMU {mt_f:.6e}, Exudyn {mt_e:.6e}, "
            f"closed form {th_max:.6e} rad (lambda {out.lam:.4f} 1/s)"
        )
    return out


@dataclass
class VerticalGrowthResult:
    """Upright top below the threshold (w3 = factor * w_c): lam_formula =
    ``growth_rate_vertical`` [1/s]; fit_fmu / fit_exudyn = ``GrowthFit`` of the tilt
    between ``lo`` and ``hi`` [rad] from a start tilt theta0 [rad]."""

    factor: float
    w3: float
    theta0: float
    lo: float
    hi: float
    lam_formula: float
    fit_fmu: mf.GrowthFit
    fit_exudyn: mf.GrowthFit | None
    wall_time: float


def vertical_growth(
    fmu_path: str | Path,
    scene: Any = "heavy_top",
    factor: float = 0.98,
    theta0: float = 1e-6,
    exudyn: bool = True,
    verbose: bool = False,
) -> VerticalGrowthResult:
    """Fit the exponential growth of a tiny tilt of the upright top below the threshold
    and compare with ``growth_rate_vertical`` (the linearisation about the vertical).

    Linear theory for xi(0) = theta0, xi'(0) = 0: |xi|^2 = theta0^2 (cosh^2(lam t) +
    r^2 sinh^2(lam t)), r = I3 w3/(2 I1 lam), so ln|xi| = const + lam t + O(e^{-2 lam t})
    and the tilt first reaches 100 theta0 when e^{-2 lam t} <~ 1e-3 (bias of the fitted
    slope <~ 2e-3 at the window start, decaying). The cubic terms change lam^2 by
    ~theta^2 (M g l + I3^2 w3^2/(4 I1)) relative to the DIFFERENCE 4 M g l I1 - I3^2 w3^2,
    i.e. by ~theta^2/(2 delta), delta = 1 - factor^2; hi = min(1e4 theta0, 0.1 sqrt(delta))
    keeps that below 5e-3. Friction scenes are run frictionless."""
    t0 = _time.perf_counter()
    sc, extra = _frictionless(_load(scene))
    if not 0.0 < factor < 1.0:
        raise ValueError(f"vertical_growth: factor must be in (0, 1) (below threshold), got {factor}")
    P = top_params(sc)
    wc = ht.sleeping_threshold(P.I1, P.I3, P.M, P.g, P.l)
    w = np.array([0.0, 0.0, factor * wc])
    lam = float(growth_rate_vertical(P, w[2]))
    lo = 100.0 * theta0
    hi = min(1e4 * theta0, 0.1 * math.sqrt(1.0 - factor**2))
    T = (math.log(hi / theta0) + 1.5) / lam
    H = min(sc.step, 0.02 / lam)
    q0 = _tilted_quaternion(theta0)
    r = _run(
        fmu_path,
        sc,
        stop_time=T,
        step=H,
        start_values=_start(w, q0, **extra),
        outputs=[f"q[{i}]" for i in (1, 2, 3, 4)],
    )
    fit_f = mf.fit_exponential_growth(r.time, mf.tilt_angle(r.vector("q")), lo, hi)
    fit_e = None
    if exudyn:
        e = _exudyn(sc, w=w, q=q0, stop_time=T, step=H)
        fit_e = mf.fit_exponential_growth(e["time"], mf.tilt_angle(e["q"]), lo, hi)
    out = VerticalGrowthResult(factor, float(w[2]), theta0, lo, hi, lam, fit_f, fit_e, _time.perf_counter() - t0)
    if verbose:
        print(
            f"upright top at {factor:.3f} w_c = {w[2]:.4f} rad/s, tilt0 {theta0:g} rad: lambda formula "
            f"{lam:.6f} 1/s, FMU fit {fit_f.rate:.6f} ({fit_f.rate / lam - 1:+.1e}) over "
            f"[{fit_f.t_start:.2f}, {fit_f.t_end:.2f}] s"
            + (f", Exudyn fit {fit_e.rate:.6f} ({fit_e.rate / lam - 1:+.1e})" if fit_e else "")
        )
    return out


@dataclass
class OnsetResult:
    """Sleeping top with friction. t_cross_formula = (I3/c) ln(w3(0)/w_c) [s] (w3 decays
    as e^{-c t/I3}, docs/theory.md §4.3); t_cross_fmu = when the FMU's w3 passes w_c;
    band [rad] = tilt level that defines the onset; max_tilt_before [rad] = largest tilt
    while w3 > w_c; t_onset [s] = first time tilt >= band; lam_onset = growth rate at
    w3(t_onset) [1/s]; delay_growth_times = (t_onset - t_cross) lam_onset;
    efolds = int_{t_cross}^{t_onset} lambda dt (linear theory's growth factor, in e-folds);
    efolds_needed = ln(band/max_tilt_before); final_tilt_max = largest tilt [rad] of the run."""

    w_c: float
    t_cross_formula: float
    t_cross_fmu: float
    band: float
    max_tilt_before: float
    t_onset: float
    lam_onset: float
    delay_growth_times: float
    efolds: float
    efolds_needed: float
    final_tilt_max: float
    exudyn_t_onset: float
    exudyn_max_tilt_before: float
    stop_time: float
    wall_time: float


def friction_onset(
    fmu_path: str | Path,
    scene: Any = "sleeping_top",
    band: float = 1e-2,
    stop_time: float | None = None,
    exudyn: bool = True,
    verbose: bool = False,
) -> OnsetResult:
    """When does the sleeping top with friction start to fall? See :class:`OnsetResult`."""
    t0 = _time.perf_counter()
    sc = _load(scene)
    if not (sc.has("friction") and sc.c_friction > 0):
        raise ValueError(f"scene {sc.name}: friction_onset needs features.friction with c > 0")
    P = top_params(sc)
    wc = ht.sleeping_threshold(P.I1, P.I3, P.M, P.g, P.l)
    w30 = float(sc.w0[2])
    if not w30 > wc:
        raise ValueError(f"scene {sc.name}: start spin {w30} rad/s is not above the threshold {wc:.4f}")
    t_cross = P.I3 / sc.c_friction * math.log(w30 / wc)
    T = sc.stop_time if stop_time is None else float(stop_time)

    def analyse(t, q, w3):
        tilt = mf.tilt_angle(q)
        tx = mf.first_exceedance(t, -w3, -wc)  # w3 falls through w_c
        before = float(np.max(tilt[t <= tx])) if np.isfinite(tx) else float(np.max(tilt))
        ton = mf.first_exceedance(t, tilt, band)
        return tilt, tx, before, ton

    r = _run(fmu_path, sc, stop_time=T, outputs=["q[1]", "q[2]", "q[3]", "q[4]", "w_body[3]"])
    tilt, tx, before, ton = analyse(r.time, r.vector("q"), r.values["w_body[3]"])
    lam_t = growth_rate_vertical(P, r.values["w_body[3]"])
    lam_on = float(np.interp(ton, r.time, lam_t)) if np.isfinite(ton) else float("nan")
    if np.isfinite(ton):
        cum = cumulative_simpson(lam_t, x=r.time, initial=0.0)
        efolds = float(np.interp(ton, r.time, cum) - np.interp(tx, r.time, cum))
    else:
        efolds = float("nan")
    e_on = e_before = float("nan")
    if exudyn:
        e = _exudyn(sc, stop_time=T)
        _, _, e_before, e_on = analyse(e["time"], e["q"], e["w_body"][:, 2])
    out = OnsetResult(
        wc,
        t_cross,
        tx,
        band,
        before,
        ton,
        lam_on,
        (ton - tx) * lam_on,
        efolds,
        math.log(band / before),
        float(np.max(tilt)),
        e_on,
        e_before,
        T,
        _time.perf_counter() - t0,
    )
    if verbose:
        print(
            f"sleeping top with friction c = {sc.c_friction:g}: w_c = {wc:.4f} rad/s crossed at "
            f"t = {tx:.4f} s (formula {t_cross:.4f} s); max tilt before {before:.3e} rad"
        )
        print(
            f"  tilt reaches {band:g} rad at t = {ton:.4f} s (Exudyn {e_on:.4f} s), "
            f"{ton - tx:.4f} s after crossing = {out.delay_growth_times:.2f}/lambda(t_onset) "
            f"(lambda {lam_on:.3f} 1/s); int lambda dt = {efolds:.2f} e-folds vs "
            f"ln(band/tilt_before) = {out.efolds_needed:.2f}; final max tilt {out.final_tilt_max:.3f} rad"
        )
    return out


# ----------------------------------------------------------------------------------
# 6. trajectories and invariants
# ----------------------------------------------------------------------------------
@dataclass
class TrajectoryComparison:
    """FMU vs Exudyn over [0, stop_time]: max_t |w_fmu - w_exu| [rad/s] and max attitude
    angle between them [rad]; est_* = error estimates of each side from a run at half
    the internal step (Richardson: |x_h - x_{h/2}| / (1 - 2^-p), p = 4 for RK4,
    6 for Exudyn's RK67), same units."""

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

    @property
    def tol_w(self) -> float:
        """Allowed max |dw| [rad/s]: 3 x the sum of both error estimates plus a round-off
        floor of 1e-12 |w| (the estimates themselves are only good to a factor ~2)."""
        return 3.0 * (self.est_fmu_w + self.est_exu_w) + 1e-12 * self.w_scale

    @property
    def tol_angle(self) -> float:
        """Allowed max attitude angle [rad], as tol_w (round-off floor 1e-12 rad)."""
        return 3.0 * (self.est_fmu_angle + self.est_exu_angle) + 1e-12


def _traj_diff(wa, qa, wb, qb) -> tuple[float, float]:
    dw = float(np.max(np.abs(np.asarray(wa) - np.asarray(wb))))
    da = float(np.max(rotation_angle_between(quat_to_matrix(qa), quat_to_matrix(qb))))
    return dw, da


def fmu_vs_exudyn(
    fmu_path: str | Path,
    scene: Any,
    stop_time: float | None = None,
    estimate_errors: bool = True,
    verbose: bool = False,
) -> TrajectoryComparison:
    """Co-simulate the scene (its inputs, start state, h_max, default method) with the FMU
    and with Exudyn RK67 at the same internal step, and compare the trajectories."""
    sc = _load(scene)
    T = sc.stop_time if stop_time is None else float(stop_time)
    outs = [f"q[{i}]" for i in (1, 2, 3, 4)] + [f"w_body[{i}]" for i in (1, 2, 3)]
    t0 = _time.perf_counter()
    r = _run(fmu_path, sc, stop_time=T, outputs=outs)
    wall_f = _time.perf_counter() - t0
    t0 = _time.perf_counter()
    e = _exudyn(sc, stop_time=T)
    wall_e = _time.perf_counter() - t0
    if e["time"].shape != r.time.shape or np.max(np.abs(e["time"] - r.time)) > 1e-9 * T:
        raise RuntimeError(f"scene {sc.name}: FMU and Exudyn communication grids differ")
    wf, qf = r.vector("w_body"), r.vector("q")
    dw, da = _traj_diff(wf, qf, e["w_body"], e["q"])
    ef_w = ef_a = ee_w = ee_a = float("nan")
    if estimate_errors:
        r2 = _run(fmu_path, sc, stop_time=T, outputs=outs, start_values={"h_max": 0.5 * sc.h_max})
        d = _traj_diff(wf, qf, r2.vector("w_body"), r2.vector("q"))
        ef_w, ef_a = d[0] / (1 - 2.0**-4), d[1] / (1 - 2.0**-4)
        e2 = _exudyn(sc, stop_time=T, h=0.5 * sc.h_max)
        d = _traj_diff(e["w_body"], e["q"], e2["w_body"], e2["q"])
        ee_w, ee_a = d[0] / (1 - 2.0**-6), d[1] / (1 - 2.0**-6)
    out = TrajectoryComparison(sc.name, T, dw, da, ef_w, ef_a, ee_w, ee_a, float(np.max(np.abs(wf))), wall_f, wall_e)
    if verbose:
        print(
            f"{sc.name}: FMU vs Exudyn over {T:g} s: max|dw| {dw:.2e} rad/s (estimates FMU "
            f"{ef_w:.1e}, Exudyn {ee_w:.1e}; tol {out.tol_w:.1e}), max angle {da:.2e} rad "
            f"(estimates {ef_a:.1e}, {ee_a:.1e}; tol {out.tol_angle:.1e}); wall FMU {wall_f:.2f} s, "
            f"Exudyn {wall_e:.2f} s"
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


def _torque_free_from(sc: Any) -> float | None:
    """Time [s] after which all of the scene's input tables stay zero (None if never)."""
    t_free = 0.0
    for v in sc.inputs.values():
        v = np.asarray(v, dtype=float)
        if v.ndim == 1:
            if np.any(v != 0.0):
                return None
            continue
        nz = np.flatnonzero(np.any(v[:, 1:] != 0.0, axis=1))
        if nz.size and nz[-1] == v.shape[0] - 1:
            return None
        if nz.size:
            t_free = max(t_free, float(v[nz[-1] + 1, 0]))
    return t_free


def conserved_drifts(
    fmu_path: str | Path,
    scene: Any,
    methods: Sequence[str] = ("rk4", "gauss4", "splitting"),
    h_factors: Sequence[float] = (1.0, 10.0),
    stop_time: float | None = None,
    verbose: bool = False,
) -> list[DriftRow]:
    """Drift of the conserved quantities per FMU method and h_max = factor * scene h_max.

    Free body (no torque): E_kin, |L|, L_world (vector, |L(t) - L(0)|/|L(0)|).
    Torque inputs: the same over the torque-free tail of the input tables.
    Heavy top: E_total (relative to the kinetic energy scale), p_phi = L_world[3] and
    p_psi = L_body[3] (both relative to |L|) — conserved (docs/theory.md §4.2).
    With friction the exact balances replace them: E_total + int c |w|^2 dt,
    p_phi + c int w_world[3] dt (the weight's torque is horizontal) and
    p_psi(t) = p_psi(0) e^{-c t/I3} (I3 w3' = -c w3 for the symmetric top); integrals by
    cumulative Simpson (error O(H^4)).
    """
    sc = _load(scene)
    codes = method_codes(fmu_path)
    T = sc.stop_time if stop_time is None else float(stop_time)
    grav, fric = sc.has("gravity"), sc.has("friction") and sc.c_friction != 0.0
    rows = []
    for mname in methods:
        if mname not in codes:
            continue
        for fac in h_factors:
            h = fac * sc.h_max
            t0 = _time.perf_counter()
            r = _run(fmu_path, sc, stop_time=T, start_values={"h_max": h, "method": codes[mname]})
            wall = _time.perf_counter() - t0
            t = r.time
            L = r.vector("L_world")
            Ln = np.linalg.norm(L, axis=1)
            d: dict[str, float] = {}
            if grav:
                E = r.values["E_total"]
                Escale = float(np.max(np.abs(r.values["E_kin"])))
                pphi, ppsi = L[:, 2], r.vector("L_body")[:, 2]
                if fric:
                    w = r.vector("w_body")
                    c = sc.c_friction
                    E = E + c * cumulative_simpson(np.sum(w * w, axis=1), x=t, initial=0.0)
                    pphi = pphi + c * cumulative_simpson(r.vector("w_world")[:, 2], x=t, initial=0.0)
                    ppsi = ppsi - ppsi[0] * np.exp(-c * t / float(sc.inertia[2, 2])) + ppsi[0]
                d["E_total"] = float(np.max(np.abs(E - E[0]))) / Escale
                d["p_phi"] = float(np.max(np.abs(pphi - pphi[0]))) / Ln[0]
                d["p_psi"] = float(np.max(np.abs(ppsi - ppsi[0]))) / Ln[0]
            else:
                t_free = _torque_free_from(sc) if sc.inputs else 0.0
                if t_free is None:
                    continue
                k = t >= t_free - 1e-12
                E = r.values["E_kin"][k]
                Lk, Lnk = L[k], Ln[k]
                d["E_kin"] = float(np.max(np.abs(E - E[0]))) / E[0]
                d["|L|"] = float(np.max(np.abs(Lnk - Lnk[0]))) / Lnk[0]
                d["L_world"] = float(np.max(np.linalg.norm(Lk - Lk[0], axis=1))) / Lnk[0]
            rows.append(DriftRow(mname, h, d, wall))
    if verbose:
        for row in rows:
            txt = ", ".join(f"{k} {v:.1e}" for k, v in row.drifts.items())
            print(f"  {sc.name} {row.method:9s} h_max {row.h_max:.0e}: {txt} ({row.wall_time:.2f} s)")
    return rows


# ----------------------------------------------------------------------------------
# report
# ----------------------------------------------------------------------------------
@dataclass
class Row:
    """One line of a scene table: values from the FMU, Exudyn and the closed form
    (nan where there is none) and a unit."""

    quantity: str
    unit: str
    fmu: float
    exudyn: float
    closed: float = float("nan")


@dataclass
class SceneReport:
    """Everything printed for one scene."""

    scene: str
    note: str
    rows: list[Row]
    comparison: TrajectoryComparison | None
    drifts: list[DriftRow]
    details: dict[str, Any]
    wall_time: float


def _final_rows(r, e, w_cf=None) -> list[Row]:
    """Rows of the final body angular velocity (FMU run r, Exudyn run e, closed form w_cf)."""
    rows = []
    for k in range(3):
        rows.append(
            Row(
                f"w_body[{k + 1}](T)",
                "rad/s",
                float(r.vector("w_body")[-1, k]),
                float(e["w_body"][-1, k]),
                float(w_cf[-1, k]) if w_cf is not None else float("nan"),
            )
        )
    return rows


def scene_report(name: str, fmu_path: str | Path, quick: bool = False) -> SceneReport:
    """Run every check that applies to the shipped scene ``name`` and collect the rows."""
    t0 = _time.perf_counter()
    sc = _load(name)
    rows: list[Row] = []
    details: dict[str, Any] = {}
    T = sc.stop_time
    if quick:
        T = min(
            T,
            {
                "free_asymmetric": 15.0,
                "symmetric_free": 5.0,
                "heavy_top": 1.0,
                "sleeping_top": 8.0,
                "torque_driven": 8.0,
            }.get(name, T),
        )
    methods = ("rk4", "gauss4", "splitting")
    note = ""
    if name == "free_asymmetric":
        tr = tennis_racket(fmu_path, sc)
        details["tennis_racket"] = tr
        k = tr.intermediate_axis
        rows.append(
            Row(
                f"tennis-racket lambda, axis {k + 1}, delta {tr.delta:g}",
                "1/s",
                tr.fit_fmu.rate,
                tr.fit_exudyn.rate,
                tr.lam_formula,
            )
        )
        for a in range(3):
            if a != k:
                rows.append(
                    Row(
                        f"max|dw|/|dw0|, spin about axis {a + 1}",
                        "-",
                        tr.growth_fmu[a],
                        tr.growth_exudyn[a],
                        tr.bound[a],
                    )
                )
        rows.append(Row(f"max|dw|/|dw0|, spin about axis {k + 1}", "-", tr.growth_fmu[k], tr.growth_exudyn[k]))
        r = _run(fmu_path, sc, stop_time=T)
        e = _exudyn(sc, stop_time=T)
        w_cf, q_cf = free_asymmetric.solve(np.diag(sc.inertia), sc.w0, sc.q0, r.time)
        note = "closed form: rbcheck.free_asymmetric (Jacobi elliptic); lambda: tennis_racket_exponent"
        rows += _final_rows(r, e, w_cf)
        rows += _traj_rows(r, e, w_cf, q_cf)
    elif name == "symmetric_free":
        st = symmetric_top_rates(fmu_path, sc, stop_time=T)
        details["symmetric_top"] = st
        rows.append(Row("Omega (w1 + i w2 ~ e^{-i Omega t})", "rad/s", st.omega_fmu, st.omega_exudyn, st.omega_formula))
        rows.append(Row("coning rate of e3 about L", "rad/s", st.coning_fmu, st.coning_exudyn, st.coning_formula))
        r = _run(fmu_path, sc, stop_time=T)
        e = _exudyn(sc, stop_time=T)
        I = np.diag(sc.inertia)
        w_cf, q_cf = free_symmetric.solve(I[0], I[2], sc.w0, sc.q0, r.time)
        note = "closed form: rbcheck.free_symmetric"
        rows += _final_rows(r, e, w_cf)
        rows += _traj_rows(r, e, w_cf, q_cf)
    elif name == "heavy_top":
        hr = heavy_top_nutation(
            fmu_path, sc, periods=min(8.2, T / ht.HeavyTop(top_params(sc), ht.init_from_state(sc.q0, sc.w0)).period)
        )
        details["nutation"] = hr
        rows.append(Row("nutation u1 = min cos(theta)", "-", hr.fmu.u1, hr.exudyn.u1, hr.u1))
        rows.append(Row("nutation u2 = max cos(theta)", "-", hr.fmu.u2, hr.exudyn.u2, hr.u2))
        rows.append(Row("nutation period", "s", hr.fmu.period, hr.exudyn.period, hr.period))
        rows.append(Row("mean precession rate", "rad/s", hr.fmu.precession, hr.exudyn.precession, hr.precession))
        rows.append(Row("max_t |u - u_closed|", "-", hr.max_du_fmu, hr.max_du_exudyn, 0.0))
        P = top_params(sc)
        rows.append(Row("I1 about the pivot (I1cm + M l^2)", "kg m^2", float("nan"), float("nan"), P.I1))
        fast = fast_top_scaling(
            fmu_path, sc, w3_values=(150.0, 300.0, 600.0, 1200.0) if quick else (150.0, 300.0, 600.0, 1200.0, 2400.0)
        )
        details["fast_top"] = fast
        note = "closed form: rbcheck.heavy_top (elliptic, I1 about the pivot)"
        r = _run(fmu_path, sc, stop_time=T)
        e = _exudyn(sc, stop_time=T)
        top = ht.HeavyTop(P, ht.init_from_state(sc.q0, sc.w0))
        rows += _final_rows(r, e, top.omega(r.time))
        rows += _traj_rows(r, e, top.omega(r.time), top.quaternion(r.time))
    elif name == "sleeping_top":
        P = top_params(sc)
        wc = ht.sleeping_threshold(P.I1, P.I3, P.M, P.g, P.l)
        above = sleeping_threshold(fmu_path, sc, 1.02, periods=4.0 if quick else 10.0)
        below = sleeping_threshold(fmu_path, sc, 0.98, periods=1.0)
        vg = vertical_growth(fmu_path, sc, 0.98)
        on = friction_onset(fmu_path, sc, stop_time=T)
        details.update(above=above, below=below, growth=vg, onset=on)
        rows.append(Row("sleeping threshold w_c = sqrt(4 M g l I1)/I3", "rad/s", float("nan"), float("nan"), wc))
        rows.append(
            Row(
                f"max tilt, w3 = 1.02 w_c, {above.stop_time:.1f} s",
                "rad",
                above.max_tilt_fmu,
                above.max_tilt_exudyn,
                above.max_tilt_closed,
            )
        )
        rows.append(
            Row(
                f"max tilt, w3 = 0.98 w_c, {below.stop_time:.1f} s",
                "rad",
                below.max_tilt_fmu,
                below.max_tilt_exudyn,
                below.max_tilt_closed,
            )
        )
        rows.append(
            Row(
                f"tilt growth rate, w3 = 0.98 w_c, tilt0 {vg.theta0:g}",
                "1/s",
                vg.fit_fmu.rate,
                vg.fit_exudyn.rate,
                vg.lam_formula,
            )
        )
        rows.append(Row("friction: w3 crosses w_c at", "s", on.t_cross_fmu, float("nan"), on.t_cross_formula))
        rows.append(Row(f"friction: tilt reaches {on.band:g} rad at", "s", on.t_onset, on.exudyn_t_onset))
        rows.append(Row("friction: max tilt while w3 > w_c", "rad", on.max_tilt_before, on.exudyn_max_tilt_before))
        rows.append(Row("friction: onset delay x lambda(t_onset)", "-", on.delay_growth_times, float("nan")))
        rows.append(
            Row("friction: int lambda dt, crossing->onset", "e-folds", on.efolds, float("nan"), on.efolds_needed)
        )
        note = (
            "closed form: rbcheck.heavy_top (elliptic, frictionless +-2 % runs; the FMU's "
            "c_friction is set to 0); last row's closed column = ln(band/max tilt before)"
        )
    elif name == "torque_driven":
        r = _run(fmu_path, sc, stop_time=T)
        e = _exudyn(sc, stop_time=T)
        rows += _final_rows(r, e)
        rows.append(Row("E_kin(T)", "J", float(r.values["E_kin"][-1]), float(e["E_kin"][-1])))
        for k in range(3):
            rows.append(
                Row(f"L_world[{k + 1}](T)", "N m s", float(r.vector("L_world")[-1, k]), float(e["L_world"][-1, k]))
            )
        note = "no closed form (piecewise-constant torque tables); drifts over the torque-free tail"
    elif name == "skewed_bar":
        # MIT 2.003J: the bearing torque that holds the rate; Exudyn: reaction of a revolute joint
        from rbcheck.skewed_bar import bearing_torque, exudyn_revolute

        I_a, I_t = float(sc.inertia[0, 0]), float(sc.inertia[1, 1])
        theta_dot = float(np.linalg.norm(sc.w0))
        for phi in (float(np.arctan2(-sc.w0[1], sc.w0[0])), 0.0, np.pi / 4, np.pi / 2):
            c, s_ = np.cos(phi / 2), np.sin(phi / 2)
            start = {
                "q[1]": c,
                "q[2]": 0.0,
                "q[3]": 0.0,
                "q[4]": s_,
                "w_body[1]": theta_dot * np.cos(phi),
                "w_body[2]": -theta_dot * np.sin(phi),
                "w_body[3]": 0.0,
            }
            r = _run(fmu_path, sc, stop_time=1.0, start_values=start)
            tau = r.vector("tau_bearing")
            ref = bearing_torque(r.time, I_a, I_t, phi, theta_dot)
            ex = exudyn_revolute(I_a, I_t, float(sc.mass), phi, theta_dot, 0.5)
            late = ex["time"] > 0.1  # after generalized-alpha's start-up transient of the multipliers
            ref_ex = bearing_torque(ex["time"][late], I_a, I_t, phi, theta_dot)
            rows.append(
                Row(
                    f"max |tau_bearing|, phi = {np.degrees(phi):.0f} deg",
                    "N m",
                    float(np.max(np.linalg.norm(tau, axis=1))),
                    float(np.max(np.linalg.norm(ex["tau_world"][late], axis=1))),
                    float(np.max(np.linalg.norm(ref, axis=1))),
                )
            )
            rows.append(
                Row(
                    f"max_t |tau - tau_formula|, phi = {np.degrees(phi):.0f} deg",
                    "N m",
                    float(np.max(np.abs(tau - ref))),
                    float(np.max(np.abs(ex["tau_world"][late] - ref_ex))),
                    0.0,
                )
            )
        note = (
            "closed form: -(I_t - I_a) thetadot^2 sin(phi) cos(phi) k_A (rbcheck.skewed_bar); Exudyn: "
            "reaction torque of a revolute joint (generalized-alpha, h = 2^-12 s, t > 0.1 s)"
        )
        details["no_free_body_comparison"] = True
    elif name == "two_frame_arm":
        # MIT 2.003J arm: the wrist (sensor) against the handout's velocity/acceleration formulas
        from rbcheck.frame_kinematics import arm_wrist

        r = _run(fmu_path, sc, stop_time=T)
        e = _exudyn(sc, stop_time=T)
        Rq0 = quat_to_matrix(sc.q0)
        omega_w = Rq0 @ sc.w0  # = Omega J + omega i_A at t = 0
        i_A0 = Rq0[:, 2]
        J = np.array([0.0, 0.0, 1.0])
        Omega = float(omega_w @ J - (omega_w @ i_A0) * (i_A0 @ J)) / float(1 - (i_A0 @ J) ** 2)
        omega = float(omega_w @ i_A0 - Omega * (i_A0 @ J))
        p_body = np.asarray(sc.sensor_point)
        L_arm = float(p_body[2])
        l_fore = float(np.hypot(p_body[0], p_body[1]))
        i_F0 = Rq0 @ np.array([p_body[0], p_body[1], 0.0]) / l_fore
        rows.append(Row("Omega (upper arm about the vertical)", "rad/s", float("nan"), float("nan"), Omega))
        rows.append(Row("omega (forearm about the upper arm)", "rad/s", float("nan"), float("nan"), omega))
        for key, unit in (("r", "m"), ("v", "m/s"), ("a", "m/s^2")):
            ref_f = arm_wrist(r.time, Omega, omega, L_arm, l_fore, J, i_A0, i_F0)[key]
            ref_e = arm_wrist(e["time"], Omega, omega, L_arm, l_fore, J, i_A0, i_F0)[key]
            first = 1 if key == "a" else 0  # Exudyn has accelerations only after its first step
            rows.append(
                Row(
                    f"max_t |wrist {key} - handout formula|",
                    unit,
                    float(np.max(np.abs(r.vector(f"sensor_{key}") - ref_f))),
                    float(np.max(np.abs(e[f"sensor_{key}"][first:] - ref_e[first:]))),
                    0.0,
                )
            )
        I = np.diag(sc.inertia)
        w_cf, q_cf = free_symmetric.solve(I[0], I[2], sc.w0, sc.q0, r.time)
        rows += _final_rows(r, e, w_cf)
        rows += _traj_rows(r, e, w_cf, q_cf)
        note = (
            "closed forms: MIT 2.003J arm (rbcheck.frame_kinematics) for the wrist, "
            "rbcheck.free_symmetric for the body; Exudyn: body outputs at the sensor point"
        )
    else:
        raise ValueError(f"unknown scene {name!r}; cross-checked scenes: {', '.join(SCENES)}")
    if details.get("no_free_body_comparison"):
        return SceneReport(name, note, rows, None, [], details, _time.perf_counter() - t0)
    cmp_ = fmu_vs_exudyn(fmu_path, sc, stop_time=T)
    drifts = conserved_drifts(fmu_path, sc, methods=methods, stop_time=T)
    return SceneReport(name, note, rows, cmp_, drifts, details, _time.perf_counter() - t0)


def _traj_rows(r, e, w_cf, q_cf) -> list[Row]:
    """Rows of the largest deviation of each run from the closed-form trajectory."""
    wf, qf = r.vector("w_body"), r.vector("q")
    Rcf = quat_to_matrix(q_cf)
    return [
        Row(
            "max_t |w - w_closed|",
            "rad/s",
            float(np.max(np.abs(wf - w_cf))),
            float(np.max(np.abs(e["w_body"] - w_cf))),
            0.0,
        ),
        Row(
            "max_t attitude angle to closed form",
            "rad",
            float(np.max(rotation_angle_between(quat_to_matrix(qf), Rcf))),
            float(np.max(rotation_angle_between(quat_to_matrix(e["q"]), Rcf))),
            0.0,
        ),
    ]


def _fmt(x: float) -> str:
    if x is None or not np.isfinite(x):
        return "-"
    return f"{x:.10g}" if abs(x) >= 1e-3 or x == 0.0 else f"{x:.4e}"


def _fmtd(a: float, b: float) -> str:
    if not (np.isfinite(a) and np.isfinite(b)):
        return "-"
    return f"{a - b:+.2e}"


def format_report(rep: SceneReport) -> str:
    """The printed table of one scene."""
    lines = [f"== {rep.scene} ==  ({rep.note})"]
    hdr = (
        f"{'quantity':46s} {'unit':7s} {'FMU':>17s} {'Exudyn':>17s} {'closed form':>17s} "
        f"{'FMU-CF':>10s} {'Exu-CF':>10s} {'FMU-Exu':>10s}"
    )
    lines += [hdr, "-" * len(hdr)]
    for r in rep.rows:
        lines.append(
            f"{r.quantity:46s} {r.unit:7s} {_fmt(r.fmu):>17s} {_fmt(r.exudyn):>17s} "
            f"{_fmt(r.closed):>17s} {_fmtd(r.fmu, r.closed):>10s} {_fmtd(r.exudyn, r.closed):>10s} "
            f"{_fmtd(r.fmu, r.exudyn):>10s}"
        )
    c = rep.comparison
    if c is not None:
        lines.append(
            f"FMU vs Exudyn RK67 over {c.stop_time:g} s: max|dw| {c.max_dw:.2e} rad/s (error estimates "
            f"FMU {c.est_fmu_w:.1e}, Exudyn {c.est_exu_w:.1e}), max attitude angle {c.max_dangle:.2e} rad "
            f"(estimates {c.est_fmu_angle:.1e}, {c.est_exu_angle:.1e})"
        )
    if rep.drifts:
        names = list(rep.drifts[0].drifts)
        lines.append(
            "conserved-quantity drift, max_t |X(t) - X(0)| / scale:"
            + (" (balances incl. friction)" if rep.scene == "sleeping_top" else "")
            + (" (torque-free tail)" if rep.scene == "torque_driven" else "")
        )
        lines.append(f"  {'method':10s} {'h_max':>8s} " + " ".join(f"{n:>10s}" for n in names) + "   wall")
        for d in rep.drifts:
            lines.append(
                f"  {d.method:10s} {d.h_max:8.0e} "
                + " ".join(f"{d.drifts[n]:10.1e}" for n in names)
                + f"  {d.wall_time:5.2f}s"
            )
    if "fast_top" in rep.details:
        f: FastTopResult = rep.details["fast_top"]
        lines.append("fast top (theta0 from the scene, theta0' = phi0' = 0); err = approx/FMU - 1:")
        lines.append(
            f"  {'w3':>6s} {'sigma':>7s} {'amp FMU':>11s} {'amp approx':>11s} {'err':>9s} "
            f"{'freq FMU':>10s} {'err':>9s} {'prec FMU':>10s} {'err':>9s} {'FMU/CF-1 max':>12s}"
        )
        for r in f.rows:
            cf = max(
                abs(r.amp_fmu / r.amp_closed - 1),
                abs(r.freq_fmu / r.freq_closed - 1),
                abs(r.prec_fmu / r.prec_closed - 1),
            )
            lines.append(
                f"  {r.w3:6.0f} {r.sigma:7.4f} {r.amp_fmu:11.5e} {r.amp_approx:11.5e} "
                f"{r.approx_error('amp'):+9.2e} {r.freq_fmu:10.4f} {r.approx_error('freq'):+9.2e} "
                f"{r.prec_fmu:10.5f} {r.approx_error('prec'):+9.2e} {cf:12.1e}"
            )
        lines.append(
            f"  log-log slope of amplitude vs w3: {f.slope_all:.4f} (all), {f.slope_asymptotic:.4f} "
            f"(sigma <= {f.sigma_max}: w3 = {', '.join(f'{w:g}' for w in f.asymptotic_w3)}); "
            f"expected -2"
        )
    lines.append(f"({rep.wall_time:.1f} s)")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """Print the cross-check tables of the shipped scenes. Returns 0.

    Options: ``--quick`` (shorter horizons, fewer spins), ``--scene NAME`` (repeatable),
    ``--fmu-dir DIR`` (reuse DIR/NAME.fmu, rebuilt when older than the sources; default:
    build fresh FMUs in a temporary directory)."""
    ap = argparse.ArgumentParser(prog="rbfmu check", description=main.__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="shorter horizons (for tests)")
    ap.add_argument("--scene", action="append", choices=SCENES, help="only this scene (repeatable)")
    ap.add_argument("--fmu-dir", type=Path, default=None, help="directory of built FMUs to reuse")
    args = ap.parse_args(list(argv) if argv is not None else None)
    names = args.scene or list(SCENES)
    t0 = _time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="rbcheck_") as tmp:
        out_dir = args.fmu_dir or Path(tmp)
        for name in names:
            sc = _load(name)
            if args.fmu_dir is not None:
                from fmu.build_fmu import ensure_fmu

                path = ensure_fmu(sc, out_dir)
            else:
                from fmu.build_fmu import build_fmu

                path = build_fmu(sc, out_dir)
            rep = scene_report(name, path, quick=args.quick)
            print(format_report(rep))
            print()
            sys.stdout.flush()
    print(f"cross-check done in {_time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
