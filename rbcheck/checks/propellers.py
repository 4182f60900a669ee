"""The quadrotor's check: hover equilibrium, yaw by the rotors' reaction and drag, world angular momentum.

Closed forms of docs/theory.md §8.6 for a '+' quadrotor whose four speed-mode propellers
(equal J, k_f, k_m, axes along body z, at equal arms) run at ±Ω_h plus the same
δ(t) = A cos(ω t + φ): the thrust moments cancel, so the body yaws about z alone, with
I_zz ω_z + Σ J Ω = L_z and dL_z/dt = −Σ k_m Ω|Ω| = −8 k_m Ω_h δ; the thrust
4 k_f (Ω_h² + δ²) lifts it by ∫ 4 k_f δ² dt / m when 4 k_f Ω_h² = m g. And the jointed
Exudyn gyrostat (rbcheck.exudyn.rotors: each propeller a body on a revolute joint, its rate
prescribed by a velocity constraint, thrust and drag loads on it) on the scene's run,
motor torques included (docs/theory.md §8.7). Units SI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from modelsrc.scene import Scene
from modelsrc.scene_inputs import Harmonic

from ..exudyn.rotors import simulate_gyrostat
from .bounds import allowed
from .common import run
from .registry import CheckOutput, Row, scene_check
from .richardson import Agreement, richardson_agreement

__all__ = ["EXUDYN_STEP", "QuadSetup", "Quadrotor", "exudyn_quadrotor", "quad_setup", "quadrotor_run"]

NAN = float("nan")
# Exudyn's internal steps (s) of the agreement rows (quick check, full check), Richardson
# from h and h/2 (trapezoidal rule, order 2); measured over the scene's 6 s, plain runs
# against the FMU: max|q − q_Exudyn| 6.9e-7, 1.7e-7, 4.3e-8 at h = 1e-3, 5e-4, 2.5e-4 s.
EXUDYN_STEP = {True: 1e-3, False: 5e-4}


@dataclass(frozen=True)
class QuadSetup:
    """The quadrotor's data: mass m (kg), I_zz (kg·m²), J (kg·m²), k_f (N·s²), k_m (N·m·s²),
    hover speed Ω_h (rad/s), differential δ(t) = A cos(ω t + φ) (rad/s, rad/s, rad), gravity g (m/s²)."""

    m: float
    I_zz: float
    J: float
    k_f: float
    k_m: float
    Omega_h: float
    A: float
    w: float
    phi: float
    g: float

    def delta(self, t: NDArray) -> NDArray:
        return self.A * np.cos(self.w * t + self.phi)

    def yaw_rate(self, t: NDArray) -> NDArray:
        """ω_z(t) (rad/s) from rest: [4 J (δ(0) − δ(t)) − 8 k_m Ω_h ∫δ] / I_zz."""
        return (4.0 * self.J * (self.delta(np.zeros(1)) - self.delta(t)) + self.L_z(t)) / self.I_zz

    def L_z(self, t: NDArray) -> NDArray:
        """L_z(t) − L_z(0) (N·m·s, world) = −8 k_m Ω_h ∫₀ᵗ δ dt (the drag torques)."""
        return -8.0 * self.k_m * self.Omega_h * self.A / self.w * (np.sin(self.w * t + self.phi) - math.sin(self.phi))

    def v_z(self, t: NDArray) -> NDArray:
        """v_z(t) (m/s) from rest: ∫ (4 k_f (Ω_h² + δ²) − m g) dt / m."""
        a, ph, w = self.A, self.phi, self.w
        int_d2 = a * a * (0.5 * t + (np.sin(2.0 * (w * t + ph)) - math.sin(2.0 * ph)) / (4.0 * w))
        return (4.0 * self.k_f * int_d2 + (4.0 * self.k_f * self.Omega_h**2 - self.m * self.g) * t) / self.m


def quad_setup(sc: Scene) -> QuadSetup:
    """The closed form's data from the scene; ValueError when it is not the symmetric '+'
    quadrotor of the module docstring."""
    rs = list(sc.rotors.values())
    specs = [sc.inputs.get(f"Omega_{n}") for n in sc.rotors]
    ok = len(rs) == 4 and all(r.speed and r.propeller for r in rs) and all(isinstance(s, Harmonic) for s in specs)
    if not ok:
        raise ValueError("the quadrotor closed form needs four speed-mode propellers with harmonic rate schedules")
    hs = [s for s in specs if isinstance(s, Harmonic)]
    r0, h0 = rs[0], hs[0]
    same = all(
        r.J == r0.J and r.k_f == r0.k_f and r.k_m == r0.k_m and np.array_equal(r.axis, [0.0, 0.0, 1.0]) for r in rs
    ) and all(h.omega == h0.omega and h.phase == h0.phase and h.amplitude[0] == h0.amplitude[0] for h in hs)
    offsets = sorted(float(h.offset[0]) for h in hs)
    arms = [float(np.linalg.norm(r.position)) for r in rs if r.position is not None]
    if not (same and offsets[0] == offsets[1] == -offsets[2] == -offsets[3] and np.ptp(arms) == 0.0):
        raise ValueError("the closed form needs equal propellers along body z at equal arms, speeds ±Ω_h + δ(t)")
    I = np.asarray(sc.inertia, dtype=float)
    return QuadSetup(
        sc.mass, float(I[2, 2]), r0.J, r0.k_f, r0.k_m, offsets[-1], float(h0.amplitude[0]), h0.omega, h0.phase,
        float(-sc.g[2]),
    )  # fmt: skip


def propeller_wrench(sc: Scene, speeds: dict[str, float]) -> tuple[NDArray, NDArray]:
    """(force (3,) N, torque about the centre of mass (3,) N·m), body frame, of the scene's
    propellers at constant rates `speeds` (rad/s by rotor name): Σ k_f Ω² g and
    Σ r × k_f Ω² g − k_m Ω|Ω| g (§8.6)."""
    F, tau = np.zeros(3), np.zeros(3)
    for n, r in sc.rotors.items():
        Om, g = speeds[n], np.asarray(r.axis, dtype=float)
        f = r.k_f * Om * Om * g
        F += f
        tau += np.cross(np.asarray(r.position, dtype=float), f) - r.k_m * Om * abs(Om) * g
    return F, tau


def tilt_balance(
    fmu_path: Path, sc: Scene, dOmega: float = 5.0, stop_time: float = 1.0, step: float = 0.002
) -> tuple[float, float, float]:
    """Rotor 1 at Ω_h + d, rotor 3 at Ω_h − d (held), the others at hover: the body pitches and
    yaws and the thrust tilts with it. World balances on the FMU's own attitude, Simpson per
    communication step: (max |L_world − L0 − ∫ R τ dt| (N·m·s), max |p − p0 − ∫ (R F + m g) dt|
    (N·s), the peak |ω| (rad/s))."""
    from scipy.integrate import cumulative_simpson

    from ..numerics.rotation_np import quat_to_matrix

    names = list(sc.rotors)
    speeds = {n: float(sc.inputs[f"Omega_{n}"].offset[0]) for n in names}  # type: ignore[union-attr]
    speeds[names[0]] += dOmega
    speeds[names[2]] -= dOmega
    r = run(fmu_path, sc, stop_time=stop_time, step=step, start_values={f"Omega_{n}": v for n, v in speeds.items()})
    F_b, tau_b = propeller_wrench(sc, speeds)
    R = quat_to_matrix(r.vector("q"))
    ang = cumulative_simpson(R @ tau_b, x=r.time, axis=0, initial=0.0)
    lin = cumulative_simpson(R @ F_b + sc.mass * np.asarray(sc.g), x=r.time, axis=0, initial=0.0)
    L, p = r.vector("L_world"), r.vector("p")
    return (
        float(np.max(np.abs(L - L[0] - ang))),
        float(np.max(np.abs(p - p[0] - lin))),
        float(np.max(np.linalg.norm(r.vector("w_body"), axis=1))),
    )


@dataclass
class Quadrotor:
    """Measured: hover (speeds held at ±Ω_h): max |x_cm − x0| (m), |v_cm| (m/s), |ω| (rad/s);
    differential speeds: max |ω_z − closed form| (rad/s) and its peak, max |ω_x|, |ω_y|
    (rad/s), max |L_world − closed form| (N·m·s), max |v_z − closed form| (m/s)."""

    hover_x: float
    hover_v: float
    hover_w: float
    yaw_err: float
    yaw_peak: float
    tilt_rate: float
    L_err: float
    vz_err: float
    tilt_L: float = NAN
    tilt_p: float = NAN
    tilt_w: float = NAN


def quadrotor_run(fmu_path: Path, sc: Scene, stop_time: float | None = None) -> Quadrotor:
    """The two runs of the check (closed forms: `QuadSetup`)."""
    qs = quad_setup(sc)
    hover = {f"Omega_{n}": float(sc.inputs[f"Omega_{n}"].offset[0]) for n in sc.rotors}  # type: ignore[union-attr]
    rh = run(fmu_path, sc, stop_time=stop_time, start_values=hover)
    r = run(fmu_path, sc, stop_time=stop_time)
    t, w, L = r.time, r.vector("w_body"), r.vector("L_world")
    L_cf = np.zeros_like(L)
    L_cf[:, 2] = qs.L_z(t)
    tilt = tilt_balance(fmu_path, sc)
    return Quadrotor(
        hover_x=float(np.max(np.abs(rh.vector("x_cm") - sc.x0))),
        hover_v=float(np.max(np.abs(rh.vector("v_cm")))),
        hover_w=float(np.max(np.abs(rh.vector("w_body")))),
        yaw_err=float(np.max(np.abs(w[:, 2] - qs.yaw_rate(t)))),
        yaw_peak=float(np.max(np.abs(w[:, 2]))),
        tilt_rate=float(np.max(np.abs(w[:, :2]))),
        L_err=float(np.max(np.abs(L - L[0] - L_cf))),
        vz_err=float(np.max(np.abs(r.vector("v_cm")[:, 2] - qs.v_z(t)))),
        tilt_L=tilt[0],
        tilt_p=tilt[1],
        tilt_w=tilt[2],
    )


def exudyn_quadrotor(fmu_path: Path, sc: Scene, h: float, stop_time: float | None = None) -> Agreement:
    """The FMU's run of the scene (rotor speeds continuous, as the driver gives them) against
    the jointed Exudyn gyrostat, Richardson from its internal steps h and h/2 (s): q, w_body
    (rad/s), x_cm (m), v_cm (m/s) and each propeller's motor torque u (N·m)."""
    r = run(fmu_path, sc, stop_time=stop_time)
    T, H = float(r.time[-1]), float(np.diff(r.time)[0])
    coarse, fine = (simulate_gyrostat(sc, stop_time=T, step=H, h=hh) for hh in (h, h / 2))
    fmu = {k: r.vector(k) for k in ("q", "w_body", "x_cm", "v_cm")}
    fmu.update({f"u_{n}": r.values[f"u_{n}"] for n in sc.rotors})
    return richardson_agreement(fmu, coarse, fine, list(fmu))


@scene_check("quadrotor")
def quadrotor(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Hover equilibrium and the yaw of differential rotor speeds against §8.6's closed forms,
    the scene's run against the jointed Exudyn gyrostat."""
    q = quadrotor_run(fmu_path, sc)
    h = EXUDYN_STEP[quick]
    ag = exudyn_quadrotor(fmu_path, sc, h)
    motors = [f"u_{n}" for n in sc.rotors]
    # tolerances (rbcheck.checks.bounds): the runs last the scene's stop time (the tilt run 1 s);
    # the sizes of the motion: a fall's distance and speed over T, the peak yaw rate, the body's
    # and the rotors' momentum, a motor's torque; the tilt balances' Simpson rule errs by
    # O((H ω)⁴) relative at its step H = 0.002 s
    qs, T = quad_setup(sc), sc.stop_time
    x_size, v_size = max(float(np.linalg.norm(sc.x0)), 0.5 * qs.g * T * T), qs.g * T
    L_size = qs.I_zz * q.yaw_peak + 4.0 * qs.J * qs.Omega_h
    tilt_L_size = float(np.max(np.diag(sc.inertia))) * q.tilt_w + 4.0 * qs.J * qs.Omega_h
    simpson = (0.002 * q.tilt_w) ** 4
    u_size = qs.k_m * qs.Omega_h**2 + qs.J * qs.A * qs.w
    est = ag.estimate
    u_diff, u_est = (max(d[k] for k in motors) for d in (ag.diff, est))
    rows = [
        Row("hover: max|x_cm - x0|", "m", q.hover_x, NAN, 0.0, allowed(sc, T, x_size)),
        Row("hover: max|v_cm|", "m/s", q.hover_v, NAN, 0.0, allowed(sc, T, v_size)),
        Row("hover: max|w|", "rad/s", q.hover_w, NAN, 0.0, allowed(sc, T, q.yaw_peak)),
        Row("yaw: max|w_z - closed form| (reaction + drag)", "rad/s", q.yaw_err, NAN, 0.0, allowed(sc, T, q.yaw_peak)),
        Row("yaw: peak |w_z|", "rad/s", q.yaw_peak, NAN),
        Row("yaw: max|w_x|, |w_y| (no tilt)", "rad/s", q.tilt_rate, NAN, 0.0, allowed(sc, T, q.yaw_peak)),
        Row("max|L_world - L0 - int drag dt|", "N m s", q.L_err, NAN, 0.0, allowed(sc, T, L_size)),
        Row("max|v_z - closed form| (thrust 4 k_f (W^2 + d^2))", "m/s", q.vz_err, NAN, 0.0, allowed(sc, T, v_size)),
        Row("tilt (rotor 1 +5, rotor 3 -5 rad/s): peak |w|", "rad/s", q.tilt_w, NAN),
        Row("tilt: max|L_world - L0 - int R tau dt|", "N m s", q.tilt_L, NAN, 0.0,
            allowed(sc, 1.0, tilt_L_size, model=simpson)),
        Row("tilt: max|p - p0 - int (R F + M g) dt|", "N s", q.tilt_p, NAN, 0.0,
            allowed(sc, 1.0, qs.m * qs.g, model=simpson)),
        Row("max|q - q_Exudyn| (scene's run)", "-", ag.diff["q"], est["q"], NAN,
            allowed(sc, T, 1.0, reference=est["q"])),
        Row("max|w - w_Exudyn|", "rad/s", ag.diff["w_body"], est["w_body"], NAN,
            allowed(sc, T, q.yaw_peak, reference=est["w_body"])),
        Row("max|x_cm - x_cm,Exudyn|", "m", ag.diff["x_cm"], est["x_cm"], NAN,
            allowed(sc, T, x_size, reference=est["x_cm"])),
        Row("max|u - u_Exudyn| (motor torques)", "N m", u_diff, u_est, NAN, allowed(sc, T, u_size, reference=u_est)),
    ]  # fmt: skip
    note = (
        "closed forms: docs/theory.md §8.6 (rbcheck.checks.propellers); hover: --set Omega_pN = +/-Omega_h; "
        "Exudyn: each propeller on a revolute joint, its speed a velocity constraint (rbcheck.exudyn.rotors), "
        f"Richardson from h = {h:g}, {h / 2:g} s; its column in the Exudyn rows: its own error estimate "
        "|x(h) - x(h/2)|"
    )
    return CheckOutput(rows, note, {"quadrotor": q, "exudyn": ag})
