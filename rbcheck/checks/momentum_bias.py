"""The momentum-bias satellite's checks: roll–yaw with wheel momentum, pitch with a free wheel, Jacobi integral.

The shipped ``momentum_bias``: a body in a circular orbit with the gravity-gradient torque and
one wheel along the orbit normal (body ±y), u = 0. Its frequencies, fitted to the FMU's
outputs rpy_lvlh as in :mod:`rbcheck.checks.orbit` (least squares over shared sinusoids, the
start guess from the discrete Fourier transform, not from the closed form), are compared with
the closed forms of :mod:`rbcheck.closed_forms.gravity_gradient` (docs/theory.md §9.8): the
roots of the roll–yaw characteristic polynomial with the wheel's momentum h_y, and the pitch
pendulum whose inertia is I_y − J. Units SI: rad, rad/s, s, J, N·m·s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.special import ellipk

from modelsrc.scene import Scene

from ..closed_forms import gravity_gradient as gg
from .bounds import allowed
from .common import run
from .orbit import fit_frequencies
from .registry import CheckOutput, Row, scene_check

SMALL = 1e-4  # rad: the start pitch of the pitch run and the start roll of the roll–yaw run
# rad/s: a start roll rate relative to LVLH, which excites the fast (nutation) mode as much as the
# slow one (from a roll angle alone the wheel's stiffness leaves the nutation ~1e-3 of the slow mode)
ROLL_RATE = 2e-6
ORBITS_ROLL_YAW = 6  # orbits of the roll–yaw run: the slow mode (~n) resolved by the DFT


def wheel_along_normal(sc: Scene) -> tuple[float, float]:
    """(J, h_y) of the scene's one wheel along body ±y: its axial inertia J (kg·m²) and its
    relative momentum along body y, h_y = J Ω₀ g_y (N·m·s; y = −orbit normal at rest in LVLH)."""
    if len(sc.rotors) != 1:
        raise ValueError(f"the momentum-bias checks need one wheel, the scene has {len(sc.rotors)}")
    (rotor,) = sc.rotors.values()
    g = np.asarray(rotor.axis, dtype=float)
    if abs(abs(g[1]) - 1.0) > 1e-12:
        raise ValueError(f"the momentum-bias checks need the wheel along body y, its axis is {g.tolist()}")
    return float(rotor.J), float(rotor.J * rotor.Omega0 * g[1])


def moments(sc: Scene) -> np.ndarray:
    """The principal moments (I_x, I_y, I_z) (kg·m², whole body) of a scene on principal axes."""
    I = np.asarray(sc.inertia, dtype=float)
    if np.count_nonzero(I - np.diag(np.diag(I))):
        raise ValueError("the momentum-bias checks need principal axes along the body axes")
    return np.diag(I).copy()


def lvlh_start_values(sc: Scene, roll_rate: float = 0.0, **angles: float) -> dict[str, float]:
    """Start values of a body at rest in LVLH turned by the 3-2-1 angles (rad), plus a roll
    rate (rad/s, body x) relative to LVLH; the wheel keeps the scene's Ω₀."""
    q, w = gg.lvlh_start(sc.orbit_rate, **angles)
    w = w + np.array([roll_rate, 0.0, 0.0])
    sv = {f"q[{k + 1}]": float(x) for k, x in enumerate(q)}
    sv.update({f"w_body[{k + 1}]": float(x) for k, x in enumerate(w)})
    return sv


@dataclass
class MomentumBiasMeasures:
    """FMU measurements (rad/s) and their closed forms: pitch (fitted, from pitch SMALL),
    pitch_closed (the pendulum's 2π/T(SMALL) with inertia I_y − J), pitch_small_closed
    (n √(3 (I_x − I_z)/(I_y − J))), roll_yaw (the two fitted frequencies) and roll_yaw_closed;
    jacobi_drift: max_t |E_J − E_J(0)| / |E_J(0)| over the scene's run (E_J mostly the wheel's);
    horizon: the longest of the runs (s), for the rows' tolerances (rbcheck.checks.bounds)."""

    pitch: float
    pitch_closed: float
    pitch_small_closed: float
    roll_yaw: tuple[float, float]
    roll_yaw_closed: tuple[float, float]
    jacobi_drift: float
    horizon: float


def measure(fmu_path: Path, sc: Scene, quick: bool = False) -> MomentumBiasMeasures:
    """Every measurement of `MomentumBiasMeasures` on the scene's FMU (its default method and settings)."""
    n, I = sc.orbit_rate, moments(sc)
    J, h_y = wheel_along_normal(sc)
    w_p = gg.pitch_frequency_free_wheel(n, I, J)
    # the pendulum φ = 2θ of §9.5 with I_y − J: period 4 K(sin² θ₀)/ω_p
    w_pendulum = w_p * math.pi / (2.0 * float(ellipk(math.sin(SMALL) ** 2)))
    T_pitch, T_roll_yaw = 5 * 2 * math.pi / w_p, (4 if quick else ORBITS_ROLL_YAW) * 2 * math.pi / n
    r = run(fmu_path, sc, stop_time=T_pitch, start_values=lvlh_start_values(sc, pitch=SMALL))
    (pitch,) = fit_frequencies(r.time, r.vector("rpy_lvlh")[:, 1], 1)
    r = run(
        fmu_path,
        sc,
        stop_time=T_roll_yaw,
        start_values=lvlh_start_values(sc, roll_rate=ROLL_RATE, roll=SMALL),
    )
    ry = fit_frequencies(r.time, r.vector("rpy_lvlh")[:, [0, 2]], 2)
    E = run(fmu_path, sc).values["E_jacobi"]
    return MomentumBiasMeasures(
        pitch=pitch,
        pitch_closed=w_pendulum,
        pitch_small_closed=w_p,
        roll_yaw=(ry[0], ry[1]),
        roll_yaw_closed=gg.momentum_bias_roll_yaw(n, I, h_y),
        jacobi_drift=float(np.max(np.abs(E - E[0])) / abs(E[0])),
        horizon=max(T_pitch, T_roll_yaw, sc.stop_time),
    )


NAN = float("nan")


@scene_check("momentum_bias", quick_stop_time=16200.0)
def momentum_bias(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """The momentum-bias satellite (docs/theory.md §9.8): pitch with a free wheel, roll–yaw
    frequencies with the wheel's momentum, the Jacobi integral."""
    m = measure(fmu_path, sc, quick)
    T = m.horizon
    # the pendulum is the planar pitch motion itself; the roll-yaw forms are linearised about rest,
    # off by O(a²) at the amplitude a = SMALL + ROLL_RATE/n the runs reach (docs/theory.md §9.8)
    a = SMALL + ROLL_RATE / sc.orbit_rate
    rows = [
        Row(f"pitch libration frequency, free wheel, theta0 {SMALL:g} rad", "rad/s", m.pitch, NAN, m.pitch_closed,
            allowed(sc, T, m.pitch_closed)),
        Row(f"roll-yaw frequency 1 (precession), roll {SMALL:g} rad", "rad/s", m.roll_yaw[0], NAN,
            m.roll_yaw_closed[0], allowed(sc, T, m.roll_yaw_closed[0], model=a**2)),
        Row(f"roll-yaw frequency 2 (nutation), roll rate {ROLL_RATE:g} rad/s", "rad/s", m.roll_yaw[1], NAN,
            m.roll_yaw_closed[1], allowed(sc, T, m.roll_yaw_closed[1], model=a**2)),
        Row("max|E_jacobi - E_jacobi(0)| / |E_jacobi(0)|, scene run", "-", m.jacobi_drift, NAN, 0.0,
            allowed(sc, T, 1.0)),
    ]  # fmt: skip
    note = (
        "closed forms: rbcheck.closed_forms.gravity_gradient (roll-yaw characteristic polynomial with the "
        "wheel's momentum, pitch pendulum with inertia I_y - J; docs/theory.md §9.8)"
    )
    return CheckOutput(rows, note, {"momentum_bias": m})
