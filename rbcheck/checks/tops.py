r"""Heavy-top checks: nutation bounds, period and precession, and the fast-top ladder.

The FMU and Exudyn runs of a gravity scene are compared with the elliptic closed form of
:mod:`rbcheck.closed_forms.heavy_top` (I1 about the PIVOT) and with the fast-top approximations
(docs/theory.md §4.2, Korean notes ⊕(5)). Units SI; the world z axis points up,
``theta`` is the tilt of the figure axis e3 from it and ``u = cos(theta) = R33``;
``q`` = unit quaternion (w, x, y, z) body -> world.

1. :func:`heavy_top_nutation` — nutation bounds u1, u2, nutation period, mean
   precession against the elliptic closed form.
2. :func:`fast_top_scaling` — the fast-top approximations over a ladder of spins.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from modelsrc.scene import Scene

from ..closed_forms import heavy_top as ht
from ..closed_forms.of_scene import top_params
from ..numerics import motion_fits as mf
from .common import exudyn_run, load, run, start_values

__all__ = [
    "FastTopResult",
    "FastTopRow",
    "HeavyTopResult",
    "NutationMeasurement",
    "closed_precession",
    "fast_top_scaling",
    "heavy_top_nutation",
    "measure_nutation",
    "top_params",
]


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


def closed_precession(top: ht.HeavyTop) -> float:
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
    scene: Scene | str | Path = "heavy_top",
    w3: float | None = None,
    periods: float = 8.2,
    step: float | None = None,
    h_max: float | None = None,
    exudyn: bool = True,
    verbose: bool = False,
) -> HeavyTopResult:
    """Run the top from the scene's start attitude with body spin (0, 0, w3) (default the
    scene's) for ``periods`` closed-form nutation periods and compare the nutation with
    :class:`rbcheck.closed_forms.heavy_top.HeavyTop`. Default step: the scene's, h_max: the scene's."""
    t0 = time.perf_counter()
    sc = load(scene)
    P = top_params(sc)
    w = np.asarray(sc.w0, dtype=float).copy()
    if w3 is not None:
        w = np.array([0.0, 0.0, float(w3)])
    top = ht.HeavyTop(P, ht.init_from_state(sc.q0, w))
    if not np.isfinite(top.period):
        raise ValueError(f"scene {sc.name} with w = {w.tolist()}: steady motion, no nutation")
    T = periods * top.period
    H = sc.step if step is None else float(step)
    h = sc.fixed_step if h_max is None else float(h_max)
    r = run(
        fmu_path,
        sc,
        stop_time=T,
        step=H,
        start_values=start_values(w, sc.q0, h_max=h),
        outputs=[f"q[{i}]" for i in (1, 2, 3, 4)],
    )
    q = r.vector("q")
    m_f = measure_nutation(r.time, q)
    du_f = float(np.max(np.abs(mf.cos_tilt(q) - top.u(r.time))))
    m_e, du_e = None, float("nan")
    if exudyn:
        e = exudyn_run(sc, w=w, stop_time=T, step=H, h=h)
        m_e = measure_nutation(e["time"], e["q"])
        du_e = float(np.max(np.abs(mf.cos_tilt(e["q"]) - top.u(e["time"]))))
    out = HeavyTopResult(
        float(w[2]),
        top.u1,
        top.u2,
        top.period,
        closed_precession(top),
        m_f,
        m_e,
        du_f,
        du_e,
        T,
        H,
        h,
        time.perf_counter() - t0,
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
    scene: Scene | str | Path = "heavy_top",
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
    t0 = time.perf_counter()
    sc = load(scene)
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
        r = run(
            fmu_path,
            sc,
            stop_time=T,
            step=H,
            start_values=start_values(w, sc.q0, h_max=h_omega / w3),
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
                prec_closed=closed_precession(top),
                prec_approx=ht.fast_top_precession_rate(P.I3, P.M, P.g, P.l, w3),
            )
        )
    ws = np.array([r.w3 for r in rows])
    amps = np.array([r.amp_fmu for r in rows])
    asym = np.array([r.sigma <= sigma_max for r in rows])
    slope_all = mf.loglog_slope(ws, amps)
    slope_asym = mf.loglog_slope(ws[asym], amps[asym]) if asym.sum() >= 2 else float("nan")
    out = FastTopResult(rows, slope_all, slope_asym, tuple(ws[asym].tolist()), sigma_max, u0, time.perf_counter() - t0)
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
