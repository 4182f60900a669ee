"""Closed forms of a rigid body in a circular orbit with the gravity-gradient torque.

Conventions of docs/theory.md §9 (Hughes, "Spacecraft Attitude Dynamics", ch. 8): LVLH x
along-track, y = −orbit normal, z to nadir; world = LVLH at t = 0; principal moments
(I_x, I_y, I_z) along body x, y, z; the body at rest in LVLH is the equilibrium.

* pitch (about y) is a pendulum in 2θ: θ̈ = −(ω_p²/2) sin 2θ, ω_p = n √(3 (I_x − I_z)/I_y);
  released from rest at θ₀ its period is 4 K(m)/ω_p with m = sin² θ₀ (§9.5);
* roll and yaw, linearised, oscillate at the two roots Ω of
  Ω⁴ − (1 + 3 k_R + k_R k_Y) n² Ω² + 4 k_R k_Y n⁴ = 0, k_R = (I_y − I_z)/I_x,
  k_Y = (I_y − I_x)/I_z (§9.6);
* `jacobi_integral`, the invariant of the orbit frame (§9.3);
* with a wheel of relative momentum h_y = J Ω g_y along body y (±orbit normal, u = 0):
  roll–yaw from I_x I_z s⁴ + (I_x K_ψ + I_z K_φ + G²) s² + K_φ K_ψ = 0, G = n (I_x − I_y + I_z) + h_y,
  K_φ = 4 n² (I_y − I_z) − n h_y, K_ψ = n² (I_y − I_x) − n h_y, and the pitch with the free
  wheel at n √(3 (I_x − I_z)/(I_y − J)) (§9.8).
The scipy reference of the same body is rbcheck.baselines.orbit.
Units SI: rad, rad/s, s, kg·m².
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.special import ellipk

from ..numerics.rotation_np import quat_mul, quat_to_matrix


def pitch_frequency(n: float, I: NDArray[np.float64]) -> float:
    """ω_p = n √(3 (I_x − I_z)/I_y) (rad/s): small pitch librations (§9.5)."""
    return n * math.sqrt(3.0 * (I[0] - I[2]) / I[1])


def pitch_period(n: float, I: NDArray[np.float64], theta0: float) -> float:
    """Period (s) of the pitch libration released from rest (relative to LVLH) at θ₀ (rad):
    4 K(m)/ω_p, m = sin² θ₀ (the pendulum φ = 2θ of amplitude 2θ₀, §9.5)."""
    return 4.0 * float(ellipk(math.sin(theta0) ** 2)) / pitch_frequency(n, I)


def roll_yaw_frequencies(n: float, I: NDArray[np.float64]) -> tuple[float, float]:
    """The two roll–yaw frequencies (rad/s), lower first, of the linearised equations (§9.6)."""
    kR = (I[1] - I[2]) / I[0]
    kY = (I[1] - I[0]) / I[2]
    b = 1.0 + 3.0 * kR + kR * kY
    disc = b * b - 16.0 * kR * kY
    if not (kR > 0 and kY > 0 and b > 0 and disc > 0):
        raise ValueError(f"roll-yaw motion not oscillatory (k_R = {kR:g}, k_Y = {kY:g})")
    s = math.sqrt(disc)
    return n * math.sqrt((b - s) / 2.0), n * math.sqrt((b + s) / 2.0)


def momentum_bias_roll_yaw(n: float, I: NDArray[np.float64], h_y: float) -> tuple[float, float]:
    """The two roll–yaw frequencies (rad/s), lower first, of a body at rest in LVLH carrying
    a wheel of relative momentum h_y = J Ω g_y (N·m·s) along body y (y = −orbit normal, so
    h_y < 0 is momentum along the orbit normal): the roots s² = −Ω² of
    I_x I_z s⁴ + (I_x K_ψ + I_z K_φ + G²) s² + K_φ K_ψ = 0 (§9.8). h_y = 0 gives
    `roll_yaw_frequencies`. Refuses a motion that is not oscillatory."""
    G = n * (I[0] - I[1] + I[2]) + h_y
    K_roll = 4.0 * n * n * (I[1] - I[2]) - n * h_y
    K_yaw = n * n * (I[1] - I[0]) - n * h_y
    a, b, c = I[0] * I[2], I[0] * K_yaw + I[2] * K_roll + G * G, K_roll * K_yaw
    disc = b * b - 4.0 * a * c
    if not (c > 0 and b > 0 and disc > 0):
        raise ValueError(f"roll-yaw motion not oscillatory (K_roll = {K_roll:g}, K_yaw = {K_yaw:g}, G = {G:g})")
    s = math.sqrt(disc)
    return math.sqrt((b - s) / (2.0 * a)), math.sqrt((b + s) / (2.0 * a))


def pitch_frequency_free_wheel(n: float, I: NDArray[np.float64], J: float) -> float:
    """n √(3 (I_x − I_z)/(I_y − J)) (rad/s): small pitch librations of a body (I whole, the
    wheel's axial inertia locked in) carrying a free wheel (u = 0) of axial inertia J along
    body y; whatever its speed, only the body without the wheel's axial inertia librates (§9.8)."""
    return n * math.sqrt(3.0 * (I[0] - I[2]) / (I[1] - J))


def lvlh_start(n: float, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(q0, ω0) of a body at rest in LVLH at t = 0 turned by the 3-2-1 angles (rad):
    q = q_z(yaw) q_y(pitch) q_x(roll) (body -> world = LVLH), ω = n ô = n Rᵀ (0, −1, 0) (body)."""

    def about(axis: int, a: float) -> np.ndarray:
        q = np.zeros(4)
        q[0], q[1 + axis] = math.cos(a / 2), math.sin(a / 2)
        return q

    q = quat_mul(quat_mul(about(2, yaw), about(1, pitch)), about(0, roll))
    return q, quat_to_matrix(q).T @ np.array([0.0, -n, 0.0])


def jacobi_integral(n: float, I: NDArray[np.float64], q: np.ndarray, w: np.ndarray, t: np.ndarray) -> np.ndarray:
    """E_J (J) along a trajectory: ½ ω_rᵀ I ω_r − ½ n² ôᵀ I ô + (3/2) n² ĉᵀ I ĉ, ω_r = ω − n ô (§9.3)."""
    out = np.empty(len(t))
    for k, (qk, wk, tk) in enumerate(zip(q, w, t)):
        R = quat_to_matrix(qk)
        o = R.T @ np.array([0.0, -1.0, 0.0])
        c = R.T @ np.array([-math.sin(n * tk), 0.0, math.cos(n * tk)])
        wr = wk - n * o
        out[k] = 0.5 * wr @ (I * wr) - 0.5 * n * n * o @ (I * o) + 1.5 * n * n * c @ (I * c)
    return out
