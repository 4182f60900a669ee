"""Closed forms of the two-body problem: Kepler's ellipse from a start state, and the extended body's deviation from it.

A point mass in the field of μ (m³/s², at the origin) started at x0, v0 (m, m/s, world)
moves on the conic of its elements (Battin, "An Introduction to the Mathematics and Methods
of Astrodynamics", ch. 4; Vallado, "Fundamentals of Astrodynamics and Applications", §2.2):
semi-major axis a = 1/(2/r0 − v0²/μ), eccentricity vector e = (v0 × h)/μ − x0/r0
(h = x0 × v0), mean motion n = √(μ/a³). With P̂ = e/|e| and Q̂ = ĥ × P̂, Kepler's equation
E − e sin E = M0 + n t (solved by Newton) gives

    x = a (cos E − e) P̂ + a √(1 − e²) sin E Q̂,
    v = (√(μ a)/r) (−sin E P̂ + √(1 − e²) cos E Q̂),   r = a (1 − e cos E).

`quadrupole_bound` bounds how far the extended body of docs/theory.md §9.7 may leave this
ellipse in one period. Units SI.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["Elements", "elements", "propagate", "quadrupole_bound"]


class Elements:
    """The ellipse of a start state: a (m), e (-), n (rad/s), period T (s), the perifocal
    unit vectors P̂ (to perigee), Q̂ (world) and the mean anomaly M0 (rad) at t = 0."""

    def __init__(self, a: float, e: float, mu: float, P: NDArray, Q: NDArray, M0: float):
        self.a, self.e, self.mu, self.P, self.Q, self.M0 = a, e, mu, P, Q, M0
        self.n = math.sqrt(mu / a**3)
        self.period = 2 * math.pi / self.n


def elements(mu: float, x0: NDArray, v0: NDArray) -> Elements:
    """The elliptic elements of the start state (x0 m, v0 m/s, world) in the field μ (m³/s²);
    ValueError for an unbound or (numerically) circular orbit, which has no perigee."""
    x0, v0 = np.asarray(x0, float), np.asarray(v0, float)
    r0 = float(np.linalg.norm(x0))
    a = 1.0 / (2.0 / r0 - float(v0 @ v0) / mu)
    if a <= 0:
        raise ValueError(f"the start state is not bound (a = {a:g} m): no ellipse")
    h = np.cross(x0, v0)
    e_vec = np.cross(v0, h) / mu - x0 / r0
    e = float(np.linalg.norm(e_vec))
    if e < 1e-8:
        raise ValueError(f"eccentricity {e:g}: the orbit is circular, perigee undefined")
    P = e_vec / e
    Q = np.cross(h / np.linalg.norm(h), P)
    cos_E = (1 - r0 / a) / e
    sin_E = float(x0 @ v0) / (e * math.sqrt(mu * a))
    E0 = math.atan2(sin_E, cos_E)
    return Elements(a, e, mu, P, Q, E0 - e * math.sin(E0))


def propagate(el: Elements, t: NDArray) -> tuple[NDArray, NDArray]:
    """Position (n, 3) m and velocity (n, 3) m/s (world) on the ellipse at times t (s)."""
    M = el.M0 + el.n * np.asarray(t, float)
    E = M + el.e * np.sin(M)
    for _ in range(50):  # Newton on E − e sin E − M; converges quadratically from this start
        dE = (E - el.e * np.sin(E) - M) / (1 - el.e * np.cos(E))
        E = E - dE
        if np.max(np.abs(dE)) < 1e-16:
            break
    s = math.sqrt(1 - el.e**2)
    r = el.a * (1 - el.e * np.cos(E))
    x = np.outer(el.a * (np.cos(E) - el.e), el.P) + np.outer(el.a * s * np.sin(E), el.Q)
    k = math.sqrt(el.mu * el.a) / r
    v = np.outer(-k * np.sin(E), el.P) + np.outer(k * s * np.cos(E), el.Q)
    return x, v


def quadrupole_bound(el: Elements, trace_I: float, m: float) -> float:
    """Bound (m) on how far the centre of mass of an extended body (tr I kg·m² about its
    centre of mass, mass m kg) leaves its start ellipse in one period (docs/theory.md §9.7).

    MacCullagh's force differs from the point mass's by at most ε = 6 tr I/(m r²) relative
    (|∂V₂/∂x| ≤ (3μ/(2r⁴))·2 tr I + (μ/(2r³))·6 λ_max/r, λ_max ≤ tr I/2, against μ m/r²),
    largest at perigee r_p = a(1 − e). A perturbing acceleration f acting for one period
    T = 2π/n moves the body by at most (Clohessy–Wiltshire, the secular terms) 4π f/n² (a
    radial f: along-track drift 2 f t/n) plus 6π² f/n² (an along-track f: (3/2) f t²), so
    with f = ε μ/r_p² and μ/n² = a³: |Δx| ≤ (4π + 6π²) ε_p a³/r_p². A factor 2 for the
    eccentric orbit (the linearisation is about a circle)."""
    r_p = el.a * (1 - el.e)
    eps = 6 * trace_I / (m * r_p**2)
    return 2 * (4 * math.pi + 6 * math.pi**2) * eps * el.a**3 / r_p**2
