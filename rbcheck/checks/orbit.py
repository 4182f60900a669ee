"""The gravity-gradient boom's checks: pitch librations, roll–yaw frequencies, Jacobi integral, scipy, Exudyn.

Measurements on a principal body in a circular orbit with the gravity-gradient torque
(the shipped ``gravity_gradient_boom``), compared with the closed forms of
:mod:`rbcheck.closed_forms.gravity_gradient` (docs/theory.md §9.5, §9.6), with the scipy reference of
:mod:`rbcheck.baselines.orbit` (DOP853 at rtol 1e-13, the nadir an explicit function of time) and with Exudyn (a free
rigid body whose load user function evaluates the torque, :mod:`rbcheck.exudyn.orbit`). Frequencies are fitted to
the FMU's outputs rpy_lvlh: sums of sinusoids by least squares (variable projection, the
start guess from the discrete Fourier transform, not from the closed form), the finite
pitch period from zero crossings. Units SI: rad, rad/s, s, J.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from modelsrc.scene import Scene

from ..baselines.orbit import reference as scipy_reference
from ..closed_forms import gravity_gradient as gg
from ..exudyn.orbit import simulate_orbit
from .bounds import allowed
from .common import run, upward_crossing_period
from .feature_checks import ROUND_OFF
from .registry import CheckOutput, Row, scene_check

SMALL = 1e-4  # rad: start angle of the linear checks; the nonlinear shift is O(SMALL²) ≈ 1e-8 relative
FINITE_PITCH = 0.5  # rad: m = sin²(0.5) = 0.23, the period 6 % longer than the small one
ORBITS_ROLL_YAW = 10  # orbits of the roll–yaw run: the two frequencies 0.63 n and 1.97 n resolved by the DFT


def _moments(sc: Scene) -> NDArray[np.float64]:
    I = np.asarray(sc.inertia, dtype=float)
    if np.count_nonzero(I - np.diag(np.diag(I))):
        raise ValueError("the orbit checks need principal axes along the body axes")
    return np.diag(I).copy()


def _start(sc: Scene, **angles: float) -> dict[str, float]:
    q, w = gg.lvlh_start(sc.orbit_rate, **angles)
    sv = {f"q[{k + 1}]": float(x) for k, x in enumerate(q)}
    sv.update({f"w_body[{k + 1}]": float(x) for k, x in enumerate(w)})
    return sv


def _dft_peaks(t: np.ndarray, X: np.ndarray, count: int) -> list[float]:
    """The `count` strongest angular frequencies (rad/s) of the columns of X sampled at the
    uniform times t: local maxima of the summed zero-padded DFT magnitudes."""
    X = X - X.mean(axis=0)
    nfft = 16 * len(t)
    spec = np.sum(np.abs(np.fft.rfft(X, n=nfft, axis=0)), axis=1)
    om = 2 * math.pi * np.fft.rfftfreq(nfft, d=t[1] - t[0])
    peaks = [i for i in range(1, len(spec) - 1) if spec[i] >= spec[i - 1] and spec[i] > spec[i + 1]]
    peaks.sort(key=lambda i: -spec[i])
    return sorted(float(om[i]) for i in peaks[:count])


def fit_frequencies(t: np.ndarray, X: np.ndarray, count: int) -> list[float]:
    """Angular frequencies (rad/s) of X(t) (columns: signals) ≈ c + Σ_k a_k cos ω_k t + b_k sin ω_k t
    with shared ω_k: least squares over ω (amplitudes by linear least squares for each ω)."""
    X = X.reshape(len(t), -1)
    guess = np.array(_dft_peaks(t, X, count))

    def residual(s: np.ndarray) -> np.ndarray:
        om = s * guess
        basis = np.column_stack([np.ones_like(t)] + [f(w * t) for w in om for f in (np.cos, np.sin)])
        coef = np.linalg.lstsq(basis, X, rcond=None)[0]
        return (X - basis @ coef).ravel() / np.max(np.abs(X))

    sol = least_squares(residual, np.ones(count), xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return sorted(float(x) for x in sol.x * guess)


@dataclass
class OrbitMeasures:
    """FMU measurements against the closed forms (rad/s, s) and the invariant and reference
    figures: pitch_small (ω fitted, SMALL start), pitch_period (FINITE_PITCH start),
    roll_yaw (the two fitted ω), jacobi_drift: max_t |E_J − E_J(0)| over the scene's run
    divided by n² tr I (the size of its terms, J); jacobi_formula: |E_J(0) of the FMU −
    numpy's| / n² tr I; scipy_dq, scipy_dw: max_t |q − q_ref| and |ω − ω_ref| / n over the
    scene's run; est_dq: the reference's own error |q(rtol 1e-13) − q(rtol 1e-12)|;
    exudyn_dq, exudyn_dw: the same for Exudyn RK67 at h = EXUDYN_H against scipy, and
    fmu_exudyn_dq, fmu_exudyn_dw the FMU against Exudyn (over one orbit under quick)."""

    pitch_small: float
    pitch_small_closed: float
    pitch_period: float
    pitch_period_closed: float
    roll_yaw: tuple[float, float]
    roll_yaw_closed: tuple[float, float]
    jacobi_drift: float
    jacobi_formula: float
    scipy_dq: float
    scipy_dw: float
    est_dq: float
    exudyn_dq: float
    exudyn_dw: float
    fmu_exudyn_dq: float
    fmu_exudyn_dw: float
    horizon: float


# s: Exudyn RK67's step, n h = 0.012; its error ~1e-13 (measured sixth order over the scene's
# run: 3.0e-6, 4.6e-8, 7.0e-10, 1.2e-11 in q at h = 200, 100, 50, 25 s)
EXUDYN_H = 10.0


def _aligned(q: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """q with each row's sign chosen to match ref's (q and −q are one rotation)."""
    return q * np.sign(np.sum(q * ref, axis=1))[:, None]


def measure(fmu_path: Path, sc: Scene, quick: bool = False) -> OrbitMeasures:
    """Every measurement of `OrbitMeasures` on the scene's FMU (its default method and settings)."""
    n, I = sc.orbit_rate, _moments(sc)
    w_p = gg.pitch_frequency(n, I)
    T_small = 5 * 2 * math.pi / w_p
    r = run(fmu_path, sc, stop_time=T_small, start_values=_start(sc, pitch=SMALL))
    (f_small,) = fit_frequencies(r.time, r.vector("rpy_lvlh")[:, 1], 1)
    T_fin = gg.pitch_period(n, I, FINITE_PITCH)
    r = run(fmu_path, sc, stop_time=(3 if quick else 5) * T_fin + 200.0, start_values=_start(sc, pitch=FINITE_PITCH))
    period = upward_crossing_period(r.time, r.vector("rpy_lvlh")[:, 1], imag_tol=1e-9)
    T_ry = (4 if quick else ORBITS_ROLL_YAW) * 2 * math.pi / n
    r = run(fmu_path, sc, stop_time=T_ry, start_values=_start(sc, roll=SMALL, yaw=SMALL))
    ry = fit_frequencies(r.time, r.vector("rpy_lvlh")[:, [0, 2]], 2)
    # the scene's own run: the invariant and the scipy reference
    r = run(fmu_path, sc)
    E = r.values["E_jacobi"]
    scale = n * n * float(np.sum(I))
    q_ref, w_ref = scipy_reference(n, I, sc.q0, sc.w0, r.time)
    q_est, _ = scipy_reference(n, I, sc.q0, sc.w0, r.time, rtol=1e-12)
    q, w = _aligned(r.vector("q"), q_ref), r.vector("w_body")
    e = simulate_orbit(sc, stop_time=2 * math.pi / n if quick else sc.stop_time, h=EXUDYN_H)
    k = len(e["time"])
    q_ex = _aligned(e["q"], q_ref[:k])
    E_np = gg.jacobi_integral(n, I, q[:1], w[:1], r.time[:1])[0]
    return OrbitMeasures(
        pitch_small=f_small,
        pitch_small_closed=w_p,
        pitch_period=period,
        pitch_period_closed=T_fin,
        roll_yaw=(ry[0], ry[1]),
        roll_yaw_closed=gg.roll_yaw_frequencies(n, I),
        jacobi_drift=float(np.max(np.abs(E - E[0]))) / scale,
        jacobi_formula=abs(float(E[0]) - E_np) / scale,
        scipy_dq=float(np.max(np.linalg.norm(q - q_ref, axis=1))),
        scipy_dw=float(np.max(np.linalg.norm(w - w_ref, axis=1))) / n,
        est_dq=float(np.max(np.linalg.norm(q_est - q_ref, axis=1))),
        exudyn_dq=float(np.max(np.linalg.norm(q_ex - q_ref[:k], axis=1))),
        exudyn_dw=float(np.max(np.linalg.norm(e["w_body"] - w_ref[:k], axis=1))) / n,
        fmu_exudyn_dq=float(np.max(np.linalg.norm(q[:k] - q_ex, axis=1))),
        fmu_exudyn_dw=float(np.max(np.linalg.norm(w[:k] - e["w_body"], axis=1))) / n,
        horizon=max(T_small, (3 if quick else 5) * T_fin + 200.0, T_ry, sc.stop_time),
    )


NAN = float("nan")


@scene_check("gravity_gradient_boom", quick_stop_time=16200.0)
def gravity_gradient_boom(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """The boom in orbit (docs/theory.md §9): pitch librations small and finite, roll–yaw
    frequencies, the Jacobi integral, the scipy reference (DOP853, rtol 1e-13)."""
    m = measure(fmu_path, sc, quick)
    T = m.horizon
    # the small pitch and the roll-yaw forms are linearised about rest: off by O(a²) at the start
    # angles a (2 SMALL for roll and yaw together); the finite pitch's period is the pendulum's own
    small, both = SMALL**2, (2 * SMALL) ** 2
    rows = [
        Row(f"pitch libration frequency, theta0 {SMALL:g} rad", "rad/s", m.pitch_small, NAN, m.pitch_small_closed,
            allowed(sc, T, m.pitch_small_closed, model=small)),
        Row(f"pitch period, theta0 {FINITE_PITCH:g} rad (4 K(sin^2 theta0) / w_p)", "s", m.pitch_period, NAN,
            m.pitch_period_closed, allowed(sc, T, m.pitch_period_closed)),
        Row(f"roll-yaw frequency 1, roll = yaw = {SMALL:g} rad", "rad/s", m.roll_yaw[0], NAN, m.roll_yaw_closed[0],
            allowed(sc, T, m.roll_yaw_closed[0], model=both)),
        Row(f"roll-yaw frequency 2, roll = yaw = {SMALL:g} rad", "rad/s", m.roll_yaw[1], NAN, m.roll_yaw_closed[1],
            allowed(sc, T, m.roll_yaw_closed[1], model=both)),
        Row("max|E_jacobi - E_jacobi(0)| / (n^2 tr I), scene run", "-", m.jacobi_drift, NAN, 0.0,
            allowed(sc, T, 1.0)),
        Row("|E_jacobi(0) - numpy's| / (n^2 tr I)", "-", m.jacobi_formula, NAN, 0.0, ROUND_OFF),
        # the Exudyn column: Exudyn's distance to the same scipy reference
        Row("max|q - q_scipy|, scene run", "-", m.scipy_dq, m.exudyn_dq, NAN, allowed(sc, T, 1.0, reference=m.est_dq)),
        Row("max|w - w_scipy| / n, scene run", "-", m.scipy_dw, m.exudyn_dw),
        Row("scipy's own error: max|q(rtol 1e-13) - q(rtol 1e-12)|", "-", m.est_dq, NAN),
        # FMU to Exudyn: through the reference, Exudyn's distance to it and the reference's own error
        Row(f"max|q - q_Exudyn|, Exudyn RK67 h = {EXUDYN_H:g} s", "-", m.fmu_exudyn_dq, NAN, NAN,
            allowed(sc, T, 1.0, reference=m.exudyn_dq + m.est_dq)),
        Row(f"max|w - w_Exudyn| / n, Exudyn RK67 h = {EXUDYN_H:g} s", "-", m.fmu_exudyn_dw, NAN),
    ]  # fmt: skip
    note = (
        "closed forms: rbcheck.closed_forms.gravity_gradient (pitch pendulum, linearised roll-yaw, Hughes "
        "ch. 8); scipy: DOP853 "
        "rtol 1e-13, nadir explicit in time; Exudyn: free body, gravity-gradient load user function "
        "(rbcheck.exudyn.orbit), over one orbit under --quick"
    )
    return CheckOutput(rows, note, {"orbit": m})
