r"""Torque-free body checks: tennis-racket growth rate and the symmetric top's rates.

Each check drives a scene's FMU through fmpy, runs the same scene in Exudyn and compares
both with the closed forms of :mod:`rbcheck.closed_forms.free_symmetric` (docs/theory.md §2.3).
Units SI; ``w`` = body angular velocity [rad/s]; ``q`` = unit quaternion (w, x, y, z)
body -> world; rates are measured from the sampled trajectories with
:mod:`rbcheck.numerics.motion_fits`.

1. :func:`tennis_racket` — growth rate of a small perturbation of a spin about the
   intermediate axis against ``tennis_racket_exponent``; boundedness about the other
   two axes against the exact invariant ``L^2 - 2 E I_k``.
2. :func:`symmetric_top_rates` — body precession rate Omega and coning rate |L|/I1.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from modelsrc.scene import Scene

from ..closed_forms import free_symmetric
from ..numerics import motion_fits as mf
from ..numerics.rotation_np import quat_to_matrix
from .common import exudyn_run, is_principal_diag, load, run, start_values

__all__ = [
    "SymmetricTopResult",
    "TennisRacketResult",
    "symmetric_top_rates",
    "tennis_racket",
    "tennis_racket_exponent",
]


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
    scene: Scene | str | Path = "free_asymmetric",
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
    t0 = time.perf_counter()
    sc = load(scene)
    I = np.asarray(sc.inertia, dtype=float)
    if not sc.torque_free or not is_principal_diag(I):
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
        r = run(
            fmu_path,
            sc,
            stop_time=T,
            step=H,
            start_values=start_values(w0, [1, 0, 0, 0]),
            outputs=[f"w_body[{i}]" for i in (1, 2, 3)],
        )
        dw = np.linalg.norm(np.delete(r.vector("w_body"), k, axis=1), axis=1)
        growth_f[k] = float(np.max(dw) / dw[0])
        e = exudyn_run(sc, w=w0, q=[1, 0, 0, 0], stop_time=T, step=H) if exudyn else None
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
    res.wall_time = time.perf_counter() - t0
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
    scene: Scene | str | Path = "symmetric_free",
    stop_time: float | None = None,
    exudyn: bool = True,
    verbose: bool = False,
) -> SymmetricTopResult:
    """Measure Omega = w3 (I1 - I3)/I1 and |L|/I1 from the FMU (and Exudyn)."""
    t0 = time.perf_counter()
    sc = load(scene)
    I = np.asarray(sc.inertia, dtype=float)
    if not sc.torque_free or not is_principal_diag(I) or I[0, 0] != I[1, 1]:
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

    r = run(fmu_path, sc, stop_time=T)
    om_m, con_m = measure(r.time, r.vector("w_body"), r.vector("q"), r.vector("L_world"))
    om_e = con_e = float("nan")
    if exudyn:
        e = exudyn_run(sc, stop_time=T)
        om_e, con_e = measure(e["time"], e["w_body"], e["q"], e["L_world"])
    out = SymmetricTopResult(om_f, om_m, om_e, con_f, con_m, con_e, T, time.perf_counter() - t0)
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
