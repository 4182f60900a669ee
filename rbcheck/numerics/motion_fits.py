"""Measure rates, periods and bounds from sampled trajectories (numpy only).

These helpers turn a sampled trajectory (an FMU or Exudyn run) into the numbers the
closed forms predict: an exponential growth rate (tennis racket, sleeping top), the
rate of a uniformly rotating phase (symmetric top), extrema and crossing times of an
oscillation (heavy-top nutation), a log-log slope (fast-top scaling). Nothing here knows
about the model: inputs are arrays, times in s, angles in rad.

Conventions as in :mod:`rbcheck.numerics.rotation_np`: quaternions scalar first ``(w, x, y, z)``,
rotating body -> world; the world z axis points up (against gravity) for the tops.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "GrowthFit",
    "cos_tilt",
    "crossing_times",
    "figure_axis_world",
    "first_exceedance",
    "fit_exponential_growth",
    "interp_cubic",
    "loglog_slope",
    "mean_period",
    "phase_rate",
    "precession_angle",
    "refined_extrema",
    "rotation_rate_about",
    "tilt_angle",
]


def _as_time_series(t: ArrayLike, y: ArrayLike, what: str) -> tuple[NDArray[np.float64], NDArray]:
    t = np.asarray(t, dtype=float)
    y = np.asarray(y)
    if t.ndim != 1 or y.shape[0] != t.size:
        raise ValueError(f"{what}: need t of shape (n,) and values with n rows, got t {t.shape}, values {y.shape}")
    if t.size < 3:
        raise ValueError(f"{what}: need at least 3 samples, got {t.size}")
    if not np.all(np.diff(t) > 0):
        raise ValueError(f"{what}: times must increase strictly")
    return t, y


# ----------------------------------------------------------------------------------
# exponential growth
# ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class GrowthFit:
    """Least-squares fit ``ln a(t) = ln a0 + rate t`` over ``[t_start, t_end]`` (s).

    rate [1/s]; n_points samples used; max_residual = largest |ln a - fit| (a measure of
    how exponential the window really is)."""

    rate: float
    log_a0: float
    t_start: float
    t_end: float
    n_points: int
    max_residual: float


def fit_exponential_growth(t: ArrayLike, amplitude: ArrayLike, lo: float, hi: float) -> GrowthFit:
    """Growth rate of ``amplitude`` over its first passage from ``lo`` to ``hi``.

    The window starts at the first sample with ``amplitude >= lo`` and ends before the
    first later sample with ``amplitude >= hi``; ``ln(amplitude)`` is fitted by a
    straight line there. Choosing ``lo`` well above the start amplitude lets decaying
    modes die out; ``hi`` well below O(1) keeps the motion linear.
    """
    t, a = _as_time_series(t, amplitude, "fit_exponential_growth")
    a = np.asarray(a, dtype=float)
    if not (0.0 < lo < hi):
        raise ValueError(f"fit_exponential_growth: need 0 < lo < hi, got lo={lo}, hi={hi}")
    above_lo = np.flatnonzero(a >= lo)
    if above_lo.size == 0:
        raise ValueError(f"fit_exponential_growth: amplitude never reaches lo={lo} (max {np.max(a):.3e})")
    i0 = int(above_lo[0])
    above_hi = np.flatnonzero(a[i0:] >= hi)
    i1 = i0 + int(above_hi[0]) if above_hi.size else a.size
    if i1 - i0 < 3:
        raise ValueError(
            f"fit_exponential_growth: only {i1 - i0} samples between lo={lo} and "
            f"hi={hi}; sample more finely or widen the window"
        )
    tt, la = t[i0:i1], np.log(a[i0:i1])
    rate, log_a0 = np.polyfit(tt, la, 1)
    res = float(np.max(np.abs(la - (rate * tt + log_a0))))
    return GrowthFit(float(rate), float(log_a0), float(tt[0]), float(tt[-1]), int(tt.size), res)


# ----------------------------------------------------------------------------------
# uniformly rotating phases
# ----------------------------------------------------------------------------------
def phase_rate(t: ArrayLike, z: ArrayLike) -> float:
    """Least-squares slope [rad/s] of the unwrapped argument of the complex signal z(t).

    Needs fewer than pi rad of phase change between samples (unwrapping)."""
    t, z = _as_time_series(t, z, "phase_rate")
    ph = np.unwrap(np.angle(np.asarray(z, dtype=complex)))
    return float(np.polyfit(t, ph, 1)[0])


def rotation_rate_about(t: ArrayLike, v: ArrayLike, axis: ArrayLike) -> float:
    """Mean rate [rad/s] at which the vectors v(t) (n, 3) turn about the fixed ``axis``
    (right-handed), from the unwrapped angle of their projection on the plane normal to
    the axis (least-squares slope)."""
    t, v = _as_time_series(t, v, "rotation_rate_about")
    n = np.asarray(axis, dtype=float).reshape(3)
    nn = float(np.linalg.norm(n))
    if not nn > 0:
        raise ValueError(f"rotation_rate_about: axis must be non-zero, got {axis!r}")
    n = n / nn
    helper = np.eye(3)[int(np.argmin(np.abs(n)))]
    e1 = np.cross(n, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    v = np.asarray(v, dtype=float)
    return phase_rate(t, v @ e1 + 1j * (v @ e2))


# ----------------------------------------------------------------------------------
# attitude of a top
# ----------------------------------------------------------------------------------
def figure_axis_world(q: ArrayLike) -> NDArray[np.float64]:
    """Body e3 in world coordinates, the third column of R(q) (q normalised first)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), w * w - x * x - y * y + z * z], -1)


def cos_tilt(q: ArrayLike) -> NDArray[np.float64]:
    """``u = cos(theta) = R33 = e3_body . e_z`` (the heavy top's nutation variable)."""
    return figure_axis_world(q)[..., 2]


def tilt_angle(q: ArrayLike) -> NDArray[np.float64]:
    """Angle theta [rad] between body e3 and world z, accurate for tiny tilts:
    ``cos^2(theta/2) = w^2 + z^2``, ``sin^2(theta/2) = x^2 + y^2``."""
    q = np.asarray(q, dtype=float)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return 2.0 * np.arctan2(np.hypot(x, y), np.hypot(w, z))


def precession_angle(q: ArrayLike) -> NDArray[np.float64]:
    """z-x-z angle phi [rad] (azimuth of the figure axis, e3_world = (sin th sin phi,
    -sin th cos phi, cos th)), unwrapped along the first axis."""
    e3 = figure_axis_world(q)
    return np.unwrap(np.arctan2(e3[..., 0], -e3[..., 1]), axis=0)


# ----------------------------------------------------------------------------------
# oscillations
# ----------------------------------------------------------------------------------
def refined_extrema(t: ArrayLike, y: ArrayLike, kind: str = "max") -> tuple[NDArray, NDArray]:
    """Interior local maxima (``kind="max"``) or minima of y(t), each refined by the
    parabola through the extreme sample and its two neighbours (vertex error
    O(dt^3 y''')). Returns (times [s], values)."""
    if kind not in ("max", "min"):
        raise ValueError(f"refined_extrema: kind must be 'max' or 'min', got {kind!r}")
    t, y = _as_time_series(t, y, "refined_extrema")
    y = np.asarray(y, dtype=float)
    s = 1.0 if kind == "max" else -1.0
    ys = s * y
    i = np.flatnonzero((ys[1:-1] > ys[:-2]) & (ys[1:-1] >= ys[2:])) + 1
    t0, t1, t2 = t[i - 1], t[i], t[i + 1]
    y0, y1, y2 = y[i - 1], y[i], y[i + 1]
    # parabola through the three points in Newton form about t1
    d01 = (y1 - y0) / (t1 - t0)
    d12 = (y2 - y1) / (t2 - t1)
    c2 = (d12 - d01) / (t2 - t0)
    c1 = d01 + c2 * (t1 - t0)  # derivative at t1
    with np.errstate(divide="ignore", invalid="ignore"):
        dt = np.where(c2 != 0.0, -c1 / (2.0 * c2), 0.0)
    dt = np.clip(dt, t0 - t1, t2 - t1)
    return t1 + dt, y1 + c1 * dt + c2 * dt * dt


def interp_cubic(t: ArrayLike, y: ArrayLike, tq: ArrayLike) -> NDArray[np.float64]:
    """Cubic Lagrange interpolation of samples y(t) at the query times tq (4-point
    stencil around each query; error O(dt^4 y'''')); tq must lie inside [t0, tn]."""
    t, y = _as_time_series(t, y, "interp_cubic")
    y = np.asarray(y, dtype=float)
    tq = np.atleast_1d(np.asarray(tq, dtype=float))
    if tq.size and (tq.min() < t[0] or tq.max() > t[-1]):
        raise ValueError(f"interp_cubic: query times [{tq.min()}, {tq.max()}] outside the samples [{t[0]}, {t[-1]}]")
    j = np.clip(np.searchsorted(t, tq) - 2, 0, t.size - 4)
    idx = j[:, None] + np.arange(4)[None, :]
    tt, yy = t[idx], y[idx]
    out = np.zeros(tq.size)
    for a in range(4):
        w = np.ones(tq.size)
        for b in range(4):
            if b != a:
                w *= (tq - tt[:, b]) / (tt[:, a] - tt[:, b])
        out += w * yy[:, a]
    return out


def crossing_times(t: ArrayLike, y: ArrayLike, level: float, direction: int = 1) -> NDArray[np.float64]:
    """Times [s] at which y(t) crosses ``level`` upwards (direction=+1) or downwards (-1):
    bracketed by the samples, then located on the cubic interpolant by a few secant
    steps (error O(dt^4) instead of linear interpolation's O(dt^2))."""
    if direction not in (1, -1):
        raise ValueError(f"crossing_times: direction must be +1 or -1, got {direction!r}")
    t, y = _as_time_series(t, y, "crossing_times")
    y = np.asarray(y, dtype=float) - level
    ys = direction * y
    i = np.flatnonzero((ys[:-1] < 0.0) & (ys[1:] >= 0.0))
    if i.size == 0:
        return np.zeros(0)
    a, b = t[i], t[i + 1]
    fa, fb = y[i], y[i + 1]
    x = a - fa * (b - a) / (fb - fa)  # linear estimate, then secant on the cubic
    xp, fp = a, fa
    for _ in range(6):
        fx = interp_cubic(t, y, x)
        denom = fx - fp
        step = np.where(denom != 0.0, fx * (x - xp) / np.where(denom != 0.0, denom, 1.0), 0.0)
        xp, fp = x, fx
        x = np.clip(x - step, a, b)
    return x


def mean_period(times: ArrayLike) -> float:
    """Period [s] of a sequence of once-per-cycle event times: least-squares slope of the
    times against the cycle index (needs at least two events)."""
    times = np.asarray(times, dtype=float)
    if times.size < 2:
        raise ValueError(f"mean_period: need at least 2 event times, got {times.size}")
    if times.size == 2:
        return float(times[1] - times[0])
    return float(np.polyfit(np.arange(times.size), times, 1)[0])


def loglog_slope(x: ArrayLike, y: ArrayLike) -> float:
    """Least-squares slope of ln y against ln x (x, y > 0)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.shape != y.shape or x.size < 2:
        raise ValueError(f"loglog_slope: need two equal-length arrays of >= 2 values, got {x.shape} and {y.shape}")
    if np.any(x <= 0) or np.any(y <= 0):
        raise ValueError(f"loglog_slope: values must be > 0, got x={x}, y={y}")
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def first_exceedance(t: ArrayLike, y: ArrayLike, level: float) -> float:
    """First time [s] at which y(t) reaches ``level`` (linear interpolation between
    samples); ``nan`` if it never does."""
    t, y = _as_time_series(t, y, "first_exceedance")
    y = np.asarray(y, dtype=float)
    k = np.flatnonzero(y >= level)
    if k.size == 0:
        return float("nan")
    i = int(k[0])
    if i == 0:
        return float(t[0])
    return float(t[i - 1] + (level - y[i - 1]) * (t[i] - t[i - 1]) / (y[i] - y[i - 1]))
