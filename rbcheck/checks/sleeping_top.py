r"""Sleeping-top checks: the threshold w_c, tilt growth below it, friction-driven onset.

The upright heavy top sleeps above ``w_c = sqrt(4 M g l I1)/I3`` (I1 about the pivot)
and falls below it (docs/theory.md §4.2, §4.3). The FMU and Exudyn runs are compared
with the elliptic closed form of :mod:`rbcheck.closed_forms.heavy_top` (run frictionless: FMU
``c_friction`` = 0) and with the linearisation about the vertical. Units SI; the world z
axis points up, the tilt is the angle [rad] of the figure axis e3 from it.

1. :func:`sleeping_threshold` — largest tilt at w3 = factor * w_c.
2. :func:`vertical_growth` — exponential tilt growth rate below the threshold.
3. :func:`friction_onset` — when friction has slowed the spin below w_c, the fall.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import cumulative_simpson

from modelsrc.scene import Scene

from ..closed_forms import heavy_top as ht
from ..numerics import motion_fits as mf
from .bounds import vertex_error
from .common import exudyn_run, frictionless, load, run, start_values, tilted_quaternion
from .tops import top_params

__all__ = [
    "GROWTH_FIT_BIAS",
    "OnsetResult",
    "SleepingResult",
    "VerticalGrowthResult",
    "friction_onset",
    "growth_rate_vertical",
    "sleeping_threshold",
    "vertical_growth",
]


# The fitted growth rate's relative biases (`vertical_growth`): the decaying e^{-2 lam t} term at
# the window's start (<~ 2e-3) and the cubic terms at its end (< 5e-3)
GROWTH_FIT_BIAS = 2e-3 + 5e-3


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
    lam = growth_rate_vertical at w3 [1/s] (0 above threshold); vertex_error [rad]: a bound
    of the error of the FMU's maximum refined between samples (rbcheck.checks.bounds.vertex_error
    of the closed-form tilt at the run's step)."""

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
    vertex_error: float = float("nan")


def sleeping_threshold(
    fmu_path: str | Path,
    scene: Scene | str | Path = "heavy_top",
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
    t0 = time.perf_counter()
    sc, extra = frictionless(load(scene))
    P = top_params(sc)
    wc = ht.sleeping_threshold(P.I1, P.I3, P.M, P.g, P.l)
    w = np.array([0.0, 0.0, factor * wc])
    q0 = tilted_quaternion(theta0)
    top = ht.HeavyTop(P, ht.TopInit(theta0, 0.0, 0.0, 0.0, 0.0, w[2]))
    th_max = 2.0 * math.atan2(math.sqrt(top.omu1), math.sqrt(top.opu1))  # u1 -> largest tilt
    T = periods * top.period
    H = sc.step if step is None else float(step)
    r = run(
        fmu_path,
        sc,
        stop_time=T,
        step=H,
        start_values=start_values(w, q0, **extra),
        outputs=[f"q[{i}]" for i in (1, 2, 3, 4)],
    )

    def max_tilt(t, q):
        tilt = mf.tilt_angle(q)
        _, vals = mf.refined_extrema(t, tilt, "max")
        return float(max(np.max(tilt), np.max(vals) if vals.size else -np.inf))

    mt_f = max_tilt(r.time, r.vector("q"))
    mt_e = float("nan")
    if exudyn:
        e = exudyn_run(sc, w=w, q=q0, stop_time=T, step=H)
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
        time.perf_counter() - t0,
        vertex_error(lambda t: np.arccos(np.clip(top.u(t), -1.0, 1.0)), min(T, top.period), H),
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
    stop_time: float = float("nan")  # s, the run's


def vertical_growth(
    fmu_path: str | Path,
    scene: Scene | str | Path = "heavy_top",
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
    t0 = time.perf_counter()
    sc, extra = frictionless(load(scene))
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
    q0 = tilted_quaternion(theta0)
    r = run(
        fmu_path,
        sc,
        stop_time=T,
        step=H,
        start_values=start_values(w, q0, **extra),
        outputs=[f"q[{i}]" for i in (1, 2, 3, 4)],
    )
    fit_f = mf.fit_exponential_growth(r.time, mf.tilt_angle(r.vector("q")), lo, hi)
    fit_e = None
    if exudyn:
        e = exudyn_run(sc, w=w, q=q0, stop_time=T, step=H)
        fit_e = mf.fit_exponential_growth(e["time"], mf.tilt_angle(e["q"]), lo, hi)
    out = VerticalGrowthResult(factor, float(w[2]), theta0, lo, hi, lam, fit_f, fit_e, time.perf_counter() - t0, T)
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
    scene: Scene | str | Path = "sleeping_top",
    band: float = 1e-2,
    stop_time: float | None = None,
    exudyn: bool = True,
    verbose: bool = False,
) -> OnsetResult:
    """When does the sleeping top with friction start to fall? See :class:`OnsetResult`."""
    t0 = time.perf_counter()
    sc = load(scene)
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

    r = run(fmu_path, sc, stop_time=T, outputs=["q[1]", "q[2]", "q[3]", "q[4]", "w_body[3]"])
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
        e = exudyn_run(sc, stop_time=T)
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
        time.perf_counter() - t0,
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
