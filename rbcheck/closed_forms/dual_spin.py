"""Closed forms of the dual-spin gyrostat: stability of a spin with a wheel along it, nutation frequency, growth rate.

A body of whole inertia diag(I_1, I_2, I_3) (rotors included, kg·m²) spins at ω_s (rad/s)
about body axis s with a wheel along s of relative momentum h_w = J Ω (N·m·s), u = 0.
Linearised about ω = ω_s e_s (docs/theory.md §8.3; Hughes, "Spacecraft Attitude
Dynamics", ch. 3, dual-spin stability; Wittenburg, "Dynamics of Multibody Systems", the
gyrostat), the transverse rates obey, for the transverse axes t1, t2,

    I_t1 ω̇_t1 = −k_2 ω_t2,   I_t2 ω̇_t2 = k_1 ω_t1,   k_i = (I_s − I_ti) ω_s + h_w

(signs for (t1, t2, s) a right-handed cyclic order), so ω̈_t1 = −(k_1 k_2 / (I_t1 I_t2)) ω_t1:
the spin is stable iff k_1 k_2 > 0, with nutation frequency sqrt(k_1 k_2 / (I_t1 I_t2))
(in the body frame), and grows at λ = sqrt(−k_1 k_2 / (I_t1 I_t2)) otherwise.
"""

from __future__ import annotations

import math

import numpy as np


def transverse_axes(s: int) -> tuple[int, int]:
    """(t1, t2): the transverse axes of spin axis s (0-based) in cyclic order (t1, t2, s)."""
    return (s + 1) % 3, (s + 2) % 3


def stability_factors(I: np.ndarray, s: int, w_s: float, h_w: float) -> tuple[float, float]:
    """(k_1, k_2) (N·m·s): k_i = (I_s − I_ti) ω_s + h_w for the transverse axes of s."""
    t1, t2 = transverse_axes(s)
    return (I[s] - I[t1]) * w_s + h_w, (I[s] - I[t2]) * w_s + h_w


def stable(I: np.ndarray, s: int, w_s: float, h_w: float) -> bool:
    """The gyrostat stability condition: (I_s ω_s + h_w − I_t1 ω_s)(I_s ω_s + h_w − I_t2 ω_s) > 0."""
    k1, k2 = stability_factors(I, s, w_s, h_w)
    return k1 * k2 > 0.0


def nutation_frequency(I: np.ndarray, s: int, w_s: float, h_w: float) -> float:
    """Nutation frequency (rad/s, body frame) of the stable spin; ValueError if unstable."""
    k1, k2 = stability_factors(I, s, w_s, h_w)
    t1, t2 = transverse_axes(s)
    if not k1 * k2 > 0.0:
        raise ValueError(f"the spin is not stable: k1 k2 = {k1 * k2:g} <= 0")
    return math.sqrt(k1 * k2 / (I[t1] * I[t2]))


def growth_rate(I: np.ndarray, s: int, w_s: float, h_w: float) -> float:
    """Exponential growth rate λ (1/s) of a transverse perturbation of the unstable spin;
    ValueError if stable."""
    k1, k2 = stability_factors(I, s, w_s, h_w)
    t1, t2 = transverse_axes(s)
    if not k1 * k2 < 0.0:
        raise ValueError(f"the spin is not unstable: k1 k2 = {k1 * k2:g} >= 0")
    return math.sqrt(-k1 * k2 / (I[t1] * I[t2]))


def transverse_ratio(I: np.ndarray, s: int, w_s: float, h_w: float) -> float:
    """max|ω_t2| / max|ω_t1| of the stable nutation started with ω_t1 only:
    sqrt(I_t1 k_1 / (I_t2 k_2))."""
    k1, k2 = stability_factors(I, s, w_s, h_w)
    t1, t2 = transverse_axes(s)
    return math.sqrt(I[t1] * k1 / (I[t2] * k2))
