"""The explicit methods' stability regions and the fixed-step rule's step, to check the sub-step rule (theory §5.4).

`stability_function(method)` is R(z) = 1 + Σ_k bᵀ A^(k−1) 𝟙 z^k of the method's tableau (RK4's
classical one; rk8's: DOP853's 12 stages from scipy, as modelsrc/integrators.py takes them):
a step of y' = λ y multiplies y by R(hλ). `left_half_radius(method)` is the smallest distance
from 0 to the edge of {|R| ≤ 1} along any ray into the left half-plane (RK4: 2.616 at 122°,
less than its 2.785 on the real and 2.828 on the imaginary axis; DOP853: 5.96 on the imaginary
axis): h·|λ| below it keeps every decaying mode decaying. `rule_step` is the largest internal
step the FMU's fixed-step rule takes at a state (h_max = 0, a communication step as large as
one likes): min(ρ_max/ρ, θ_max/|ω|) from the generated model_rate.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from modelsrc.methods import METHODS

RK4_TABLEAU = (np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]]), np.array([1, 2, 2, 1]) / 6)


def tableau(method: str) -> tuple[np.ndarray, np.ndarray]:
    """(A, b) of an explicit method: rk4 or rk8 (DOP853's 8th-order propagator)."""
    if method == "rk4":
        return RK4_TABLEAU
    if method == "rk8":
        from scipy.integrate._ivp import dop853_coefficients as dop

        return np.array(dop.A[:12, :12], float), np.array(dop.B, float)
    raise ValueError(f"no explicit tableau for {method}")


@functools.cache
def stability_coefficients(method: str) -> np.ndarray:
    """The coefficients c_k of R(z) = Σ c_k z^k, lowest first."""
    A, b = tableau(method)
    c, v = [1.0], np.ones(len(b))
    for _ in range(len(b)):
        c.append(float(b @ v))
        v = A @ v
    return np.array(c)


def stability_function(method: str, z: np.ndarray | complex) -> np.ndarray:
    """R(z) of the method (complex)."""
    return np.polyval(stability_coefficients(method)[::-1], np.asarray(z, dtype=complex))


def ray_radius(method: str, angle: float, r_max: float = 12.0, n: int = 24001) -> float:
    """The distance from 0 along the ray at `angle` (rad) to where |R| first exceeds 1."""
    r = np.linspace(1e-6, r_max, n)
    over = np.abs(stability_function(method, r * np.exp(1j * angle))) > 1 + 1e-12
    return float(r[np.argmax(over)]) if over.any() else math.inf


@functools.cache
def left_half_radius(method: str) -> float:
    """min over rays into the closed left half-plane (90° to 180°, every 0.5°) of ray_radius."""
    return min(ray_radius(method, a) for a in np.radians(np.linspace(90.0, 180.0, 181)))


def rule_step(method: str, rate: float, spin: float) -> float:
    """The largest internal step (s) of the fixed-step rule at a state whose model_rate is
    (rate, spin): h·rate ≤ ρ_max and h·spin ≤ θ_max (h_max = 0, H → ∞); inf without either."""
    m = METHODS[method]
    return min(m.rate_limit / rate if rate > 0 else math.inf, m.rotation_limit / spin if spin > 0 else math.inf)
