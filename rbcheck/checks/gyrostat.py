"""The dual-spin gyrostat's checks: momentum under motor torques, nutation, growth on the unstable side, Exudyn.

Measurements on a scene with one wheel along a principal spin axis (the shipped
``dual_spin``), compared with the closed forms of :mod:`rbcheck.closed_forms.dual_spin` and with the
jointed Exudyn model of :mod:`rbcheck.exudyn.rotors`. Units SI; ω body frame (rad/s),
L world frame (N·m·s).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from modelsrc.scene import Scene

from ..closed_forms import dual_spin as ds
from ..exudyn.rotors import simulate_gyrostat
from .balances import balances, held_run
from .common import run, upward_crossing_period

# The motor-torque schedule of the conservation check (N·m, on wheel J = 1 kg·m²): a
# spin-up, a pause, a reversal, held over each communication step by the driver.
U_SCHEDULE = ((0.0, 2.0), (4.0, 0.0), (6.0, -3.0), (8.0, 1.0))


def motor_torque(t: float) -> float:
    """The piecewise-constant motor torque u(t) (N·m) of U_SCHEDULE."""
    return [u for t0, u in U_SCHEDULE if t >= t0 - 1e-12][-1]


@dataclass(frozen=True)
class SpinSetup:
    """The scene's wheel and spin: its name, spin axis s (0-based body axis along the wheel),
    principal moments I (kg·m²), spin rate ω_s (rad/s) and wheel momentum h_w = J Ω0 (N·m·s)."""

    wheel: str
    s: int
    I: np.ndarray
    w_s: float
    h_w: float
    J: float


def spin_setup(sc: Scene) -> SpinSetup:
    """The one wheel of the scene along a body axis; ValueError otherwise."""
    if len(sc.rotors) != 1:
        raise ValueError(f"the dual-spin checks need one wheel, the scene has {len(sc.rotors)}")
    ((name, r),) = sc.rotors.items()
    s = int(np.argmax(np.abs(r.axis)))
    if abs(abs(r.axis[s]) - 1.0) > 1e-12 or np.count_nonzero(np.diag(np.diag(sc.inertia)) - sc.inertia):
        raise ValueError("the dual-spin checks need the wheel along a principal body axis")
    sign = float(np.sign(r.axis[s]))
    return SpinSetup(name, s, np.diag(sc.inertia).copy(), float(sc.w0[s]), sign * r.J * r.Omega0, r.J)


def with_start(sc: Scene, eps: float, w_s: float | None = None, Omega0: float | None = None) -> Scene:
    """The scene with the start rate ε along the first transverse axis and ω_s along the
    spin axis (optionally another spin and wheel rate)."""
    sp = spin_setup(sc)
    w0 = np.zeros(3)
    w0[sp.s] = sp.w_s if w_s is None else w_s
    w0[ds.transverse_axes(sp.s)[0]] = eps
    rotors = sc.rotors
    if Omega0 is not None:
        rotors = {sp.wheel: dataclasses.replace(sc.rotors[sp.wheel], Omega0=Omega0)}
    return dataclasses.replace(sc, w0=w0, rotors=rotors)


def _start_values(sc: Scene) -> dict[str, float]:
    sv = {f"w_body[{k + 1}]": float(x) for k, x in enumerate(sc.w0)}
    sv.update({f"Omega_{n}": r.Omega0 for n, r in sc.rotors.items()})
    return sv


@dataclass
class Conservation:
    """max_t |L_world(t) − L_world(0)| / |L_world(0)| with u = 0 and under U_SCHEDULE (FMU),
    and with U_SCHEDULE the change of the wheel's rate it causes (rad/s, to show u acted)."""

    rel_drift_free: float
    rel_drift_driven: float
    wheel_rate_change: float


def momentum_conservation(fmu_path: Path, sc: Scene, stop_time: float = 10.0) -> Conservation:
    """Total world angular momentum of the FMU's run with u = 0 and with the motor-torque
    schedule U_SCHEDULE (docs/theory.md §8.1: conserved whatever u)."""
    sp = spin_setup(sc)
    out = []
    for fn in (None, lambda t, y: {f"u_{sp.wheel}": motor_torque(t)}):
        r = run(fmu_path, sc, stop_time=stop_time, input_fn=fn)
        L = r.vector("L_world")
        out.append((float(np.max(np.linalg.norm(L - L[0], axis=1)) / np.linalg.norm(L[0])), r))
    Om = out[1][1].values[f"Omega_{sp.wheel}"]
    return Conservation(out[0][0], out[1][0], float(np.max(np.abs(Om - Om[0]))))


@dataclass
class MotorBalance:
    """The work and angular-momentum balances (rbcheck.checks.balances) of the scene under
    U_SCHEDULE given as its u table: residuals max |ΔE − ∫ Σ u Ω dt| (J) with the motor
    power and without it (the wrong balance, to show the term matters), max |ΔL_world| (N·m·s),
    the motor work ∫ Σ u Ω dt (J)."""

    work: float
    work_without_motor: float
    angular_momentum: float
    work_done: float


def scheduled(sc: Scene) -> Scene:
    """The scene with its wheel's motor torque scheduled as U_SCHEDULE (a table, N·m)."""
    sp = spin_setup(sc)
    return dataclasses.replace(sc, inputs={f"u_{sp.wheel}": np.array(U_SCHEDULE, dtype=float)})


def motor_balance(fmu_path: Path, sc: Scene, stop_time: float = 10.0) -> MotorBalance:
    """E(t) − E(0) = ∫ Σ u Ω_rel dt and L_world constant (docs/theory.md §8.2) on a held run of
    the scene with U_SCHEDULE as its schedule (the driver feeds it as the scene file would)."""
    s2 = scheduled(sc)
    hr = held_run(fmu_path, s2, stop_time)
    b, wrong = balances(s2, hr), balances(s2, hr, motor_power=False)
    return MotorBalance(b.work, wrong.work, b.angular_momentum, b.work_done)


def _zero_crossing_frequency(t: np.ndarray, x: np.ndarray) -> float:
    """Angular frequency (rad/s) from the first and last upward zero crossings of x(t)."""
    return 2.0 * math.pi / upward_crossing_period(t, x)


@dataclass
class Nutation:
    """Nutation frequency (rad/s) of a small transverse perturbation ε: FMU, Exudyn and closed form."""

    eps: float
    fmu: float
    exudyn: float
    closed: float


NUTATION_EPS = 1e-5  # rad/s: the nonlinear shift of the frequency is O(ε²/ω_s²) ≈ 1e-10 relative


def nutation(fmu_path: Path, sc: Scene, stop_time: float = 60.0, exudyn: bool = True) -> Nutation:
    """The nutation frequency of the scene's spin started with ε = NUTATION_EPS along the first
    transverse axis, from the zero crossings of that rate (docs/theory.md §8.3)."""
    sp = spin_setup(sc)
    t1 = ds.transverse_axes(sp.s)[0]
    s2 = with_start(sc, NUTATION_EPS)
    r = run(fmu_path, s2, stop_time=stop_time, start_values=_start_values(s2))
    f_fmu = _zero_crossing_frequency(r.time, r.vector("w_body")[:, t1])
    f_ex = math.nan
    if exudyn:  # Richardson from h and h/2: the trapezoidal rule's phase error at the wheel's
        # 101 rad/s is (ω h)²/12 ≈ 8e-4 at h = 1e-3, removed to O(h⁴)
        f = [
            _zero_crossing_frequency(e["time"], e["w_body"][:, t1])
            for e in (simulate_gyrostat(s2, stop_time=stop_time, h=hh) for hh in (1e-3, 5e-4))
        ]
        f_ex = (4.0 * f[1] - f[0]) / 3.0
    return Nutation(NUTATION_EPS, f_fmu, f_ex, ds.nutation_frequency(sp.I, sp.s, sp.w_s, sp.h_w))


@dataclass
class Growth:
    """A transverse perturbation ε on either side of the stability boundary: wheel momenta
    (N·m·s), the measured growth rate λ (1/s) on the unstable side against the closed form,
    and max_t |ω_⊥| / ε on both sides (the stable side's against its closed-form bound
    max(1, transverse_ratio))."""

    h_unstable: float
    rate_fmu: float
    rate_closed: float
    growth_unstable: float
    h_stable: float
    growth_stable: float
    bound_stable: float


GROWTH_EPS = 1e-7  # rad/s: the unstable run stays linear (|ω_⊥| < 1e-3 ω_s) over the fit


def growth(fmu_path: Path, sc: Scene, h_unstable: float = 0.0, fit: tuple[float, float] = (5.0, 25.0)) -> Growth:
    """λ fitted to acosh(ω_t1 / ε) = λ t (exact for the linearised unstable spin started with
    ω_t1 = ε) over `fit` (s) with the wheel at h_unstable; and the scene's own (stable)
    wheel's bounded transverse rate over the same time."""
    sp = spin_setup(sc)
    t1, t2 = ds.transverse_axes(sp.s)
    unstable = with_start(sc, GROWTH_EPS, Omega0=h_unstable / sp.J)
    r = run(fmu_path, unstable, stop_time=fit[1], start_values=_start_values(unstable))
    sel = r.time >= fit[0]
    y = np.arccosh(np.maximum(r.vector("w_body")[sel, t1] / GROWTH_EPS, 1.0))
    rate = float(np.polyfit(r.time[sel], y, 1)[0])
    wu = r.vector("w_body")
    g_unstable = float(np.max(np.hypot(wu[:, t1], wu[:, t2])) / GROWTH_EPS)
    stable_sc = with_start(sc, GROWTH_EPS)
    rs = run(fmu_path, stable_sc, stop_time=fit[1], start_values=_start_values(stable_sc))
    w = rs.vector("w_body")
    g = float(np.max(np.hypot(w[:, t1], w[:, t2])) / GROWTH_EPS)
    bound = max(1.0, ds.transverse_ratio(sp.I, sp.s, sp.w_s, sp.h_w))
    return Growth(h_unstable, rate, ds.growth_rate(sp.I, sp.s, sp.w_s, h_unstable), g_unstable, sp.h_w, g, bound)


@dataclass
class ExudynAgreement:
    """max_t |FMU − Exudyn| of ω (rad/s), q and the wheel's relative rate (rad/s), Exudyn
    Richardson-extrapolated from steps h and h/2 (trapezoidal rule, order 2), and the size
    of Exudyn's own error estimate |x(h/2) − x(h)| (same units), for a constant motor torque u."""

    u: float
    dw: float
    dq: float
    dOmega: float
    est_w: float
    est_q: float
    est_Omega: float


def exudyn_agreement(fmu_path: Path, sc: Scene, u: float, stop_time: float = 2.0, h: float = 2e-4) -> ExudynAgreement:
    """The FMU (scene defaults) against the jointed Exudyn gyrostat with the motor torque u
    (N·m) held from t = 0."""
    sp = spin_setup(sc)
    fn: Callable[[float, Mapping[str, float]], Mapping[str, float]] = lambda t, y: {f"u_{sp.wheel}": u}
    r = run(fmu_path, sc, stop_time=stop_time, input_fn=fn)
    coarse, fine = (simulate_gyrostat(sc, stop_time=stop_time, h=hh, input_fn=fn) for hh in (h, h / 2))
    key = f"Omega_{sp.wheel}"

    def cmp(fmu: np.ndarray, name: str) -> tuple[float, float]:
        a, b = np.asarray(coarse[name]), np.asarray(fine[name])
        rich = (4.0 * b - a) / 3.0
        return float(np.max(np.abs(fmu - rich))), float(np.max(np.abs(b - a)))

    dw, ew = cmp(r.vector("w_body"), "w_body")
    dq, eq = cmp(r.vector("q"), "q")
    dO, eO = cmp(r.values[key], key)
    return ExudynAgreement(u, dw, dq, dO, ew, eq, eO)
