"""Closed forms of the speed-command motor (rotor mode "command"): a step command followed with a first-order lag.

The motor of multirotor simulators (docs/theory.md §8.8; RotorS, Furrer et al. 2016;
Flightmare, Song et al. 2020): the rotor's rate Ω relative to the body follows a held
command Ω_cmd with the time constant τ_m,

    Ω̇ = (Ω_cmd − Ω)/τ_m   ⇒   Ω(t) = Ω_cmd + (Ω(0) − Ω_cmd) e^(−t/τ_m),

whatever the body does (the law holds Ω relative to the body). On a free body at rest
with one rotor along a principal axis s (whole inertia I_s about it, rotors included) the
motion stays about s and the total angular momentum about s, I_s ω + J Ω, stays 0: the
body turns back at ω(t) = −J Ω(t)/I_s, and the motor torque is
u = J (Ω̇ + ω̇) = J (1 − J/I_s) Ω̇. Fixed-step RK4 on the lag makes the global error
(Ω_cmd − Ω(0)) (t/τ) e^(−t/τ) (h/τ)⁴/120 to leading order (local error z⁵/120 of the
stability polynomial at z = h/τ; the largest over t at t = τ, `rk4_error_bound`). SI units.
"""

from __future__ import annotations

import math

import numpy as np


def lag_rate(t: np.ndarray, Omega_cmd: float, tau_m: float, Omega0: float = 0.0) -> np.ndarray:
    """Ω(t) (rad/s): the rate under a constant command Ω_cmd (rad/s) with time constant tau_m (s)."""
    return Omega_cmd + (Omega0 - Omega_cmd) * np.exp(-np.asarray(t, dtype=float) / tau_m)


def spin_up_from_rest(t: np.ndarray, Omega_cmd: float, tau_m: float, J: float, I_s: float) -> dict[str, np.ndarray]:
    """A free body and its rotor at rest at t = 0, a step command Ω_cmd (rad/s) along the
    principal axis s (whole inertia I_s, kg·m²; rotor inertia J, kg·m²; lag tau_m, s):
    "Omega" Ω(t) (rad/s), "w" the body's rate about s (rad/s, from I_s ω + J Ω = 0),
    "u" the motor torque J (1 − J/I_s) Ω̇ (N·m)."""
    Om = lag_rate(t, Omega_cmd, tau_m)
    Om_dot = (Omega_cmd - Om) / tau_m
    return {"Omega": Om, "w": -J * Om / I_s, "u": J * (1.0 - J / I_s) * Om_dot}


def rk4_error_bound(step_size: float, Omega_cmd: float, tau_m: float, Omega0: float = 0.0) -> float:
    """Leading-order bound (rad/s) of fixed-step RK4's global error in Ω over any horizon:
    |Ω_cmd − Ω(0)| max_t (t/τ) e^(−t/τ) (h/τ)⁴/120 = |Ω_cmd − Ω(0)| e^(−1) (h/τ)⁴/120."""
    return abs(Omega_cmd - Omega0) * math.exp(-1.0) * (step_size / tau_m) ** 4 / 120.0
