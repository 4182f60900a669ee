"""scipy baselines of the scenes whose reference point moves: free flight with forces at points, the moving pivot.

Independent of the FMU (nothing from ``modelsrc`` physics or ``fmu``; a scene is read
as data, its inputs through ``Scene.input_at`` / ``Scene.input_mean``). The equations are written here again
in numpy (docs/theory.md §7), state y = (q, ω, x, v): q unit quaternion body -> world,
ω body angular velocity (rad/s), and the position x (m) and velocity v (m/s), world
frame, of the centre of mass (``translation``) or of the pivot (``moving_pivot``):

    free body:    q̇ = ½ q ⊗ (0, ω),  I ω̇ = τ − ω × I ω,  ẋ = v,  M v̇ = Σ F + M g
                  τ = τ_body + Rᵀ τ_world + Σ r_i × F_i (body) − c ω   (I about the centre of mass)
    moving pivot: J ω̇ = r_cm × Rᵀ M (g − a_B) + τ − ω × J ω,  ẋ_B = v_B,  v̇_B = a_B
                  (J = I + M(|r|² 1 − r rᵀ) about the pivot: Euler's equations about a moving point)
    central field (``central_gravity``, μ at the origin, docs/theory.md §9.7): the force and
    torque written out by hand here, where the FMU lets CasADi differentiate the potential:
                  F = −μ M x/r³ − (3μ/(2 r⁵)) ((tr I − 5 xᵀ I_w x / r²) x + 2 I_w x),  I_w = R I Rᵀ
                  τ = (3μ/r⁵) ρ × (I ρ),  ρ = Rᵀ x

`integrate` dispatches any scene: ``rbcheck.baselines.gyrostat`` for a body with rotors
(about a fixed point), these equations when the reference point moves,
``rbcheck.baselines.rigid_body.integrate_scipy`` otherwise.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..numerics.rotation_np import cross3, quat_to_matrix, quat_to_matrix1
from .gyrostat import integrate_gyrostat
from .rigid_body import Trajectory, integrate_scipy, solve_restarted

__all__ = ["MotionODE", "central_field", "central_potential", "integrate", "moves"]


def moves(scene: Any) -> bool:
    """True when the scene's reference point moves (translation or moving_pivot)."""
    f = getattr(scene, "features", ())
    return "translation" in f or "moving_pivot" in f


class MotionODE:
    """Right-hand side of a free body or a top on a moving pivot (module docstring),
    with the inputs held by `hold` between calls."""

    def __init__(self, scene: Any):
        self.sc = scene
        f = scene.features
        self.pivot = "moving_pivot" in f
        self.m = float(scene.mass)
        self.g = np.asarray(scene.g, dtype=float) if "gravity" in f else np.zeros(3)
        self.c = float(scene.c_friction) if "friction" in f else 0.0
        I = np.asarray(scene.inertia, dtype=float)
        self.r = np.asarray(scene.r_cm, dtype=float) if self.pivot else np.zeros(3)
        self.J = I + self.m * (float(self.r @ self.r) * np.eye(3) - np.outer(self.r, self.r))
        self.Jinv = np.linalg.inv(self.J)
        self.points = {n: (np.asarray(p.point, dtype=float), p.frame) for n, p in scene.force_points.items()}
        self.mu = float(scene.mu) if "central_gravity" in f else 0.0
        self.held = "prescribed_rate" in f  # ω̇ = 0 (docs/theory.md §4.4)
        self.nfev = 0
        self.hold({})

    def hold(self, u: dict[str, np.ndarray]) -> None:
        """Hold the inputs u (name -> 3-vector: N·m, N, m/s² in their frames) until the next call."""
        z = np.zeros(3)
        self.tau_b = np.asarray(u.get("tau_body", z), dtype=float).copy()
        self.tau_w = np.asarray(u.get("tau_world", z), dtype=float)
        self.F_b = np.asarray(u.get("f_body", z), dtype=float).copy()  # body-frame forces at the centre of mass
        self.F_w = np.asarray(u.get("f_world", z), dtype=float).copy() + self.m * self.g
        self.world_points = []
        for name, (r, frame) in self.points.items():
            f = np.asarray(u.get(f"f_{name}", z), dtype=float)
            if frame == "body":  # constant in the body: its force and moment (body) add up once
                self.F_b += f
                self.tau_b += np.cross(r, f)
            else:
                self.F_w += f
                self.world_points.append((r, f))
        self.a_B = np.asarray(u.get("a_pivot", z), dtype=float)

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt at y = (q, ω, x, v) (13,); t (s) unused (inputs are held)."""
        self.nfev += 1
        q, w = y[0:4], y[4:7]
        R = quat_to_matrix1(q)  # of q/|q|: scipy does not keep |q| = 1
        tau = self.tau_b + R.T @ self.tau_w - self.c * w
        for r, f in self.world_points:
            tau = tau + cross3(r, R.T @ f)
        if self.pivot:  # gravity g − a_B about the moving pivot (docs/theory.md §7.3)
            tau = tau + cross3(self.r, R.T @ (self.m * (self.g - self.a_B)))
            acc = self.a_B
        else:
            acc = (self.F_w + R @ self.F_b) / self.m
        if self.mu:
            F_c, tau_c = central_field(self.mu, self.m, self.J, R, y[7:10])
            acc, tau = acc + F_c / self.m, tau + tau_c
        w_dot = np.zeros(3) if self.held else self.Jinv @ (tau - cross3(w, self.J @ w))
        a, b, c, d = q
        q_dot = 0.5 * np.array(
            [-b * w[0] - c * w[1] - d * w[2], a * w[0] + c * w[2] - d * w[1], a * w[1] + d * w[0] - b * w[2],
             a * w[2] + b * w[1] - c * w[0]]
        )  # fmt: skip
        return np.concatenate([q_dot, w_dot, y[10:13], acc])

    def invariants(self, Y: np.ndarray) -> dict[str, np.ndarray]:
        """E_kin (J: ½ M |v_cm|² + ½ ωᵀ I ω), E_total (J, with −M g·x_cm), L_world (N·m·s,
        about the centre of mass or the pivot), x_cm (m) and |q| of states Y (n, 13)."""
        R = quat_to_matrix(Y[:, :4])
        w = Y[:, 4:7]
        r_w = R @ self.r
        x_c = Y[:, 7:10] + r_w
        v_c = Y[:, 10:13] + np.cross(np.einsum("nij,nj->ni", R, w), r_w)
        I_cm = self.J - self.m * (float(self.r @ self.r) * np.eye(3) - np.outer(self.r, self.r))
        E_kin = 0.5 * self.m * np.einsum("ni,ni->n", v_c, v_c) + 0.5 * np.einsum("ni,ij,nj->n", w, I_cm, w)
        L_world = np.einsum("nij,nj->ni", R, w @ self.J.T)
        out = {
            "E_kin": E_kin,
            "E_total": E_kin - self.m * x_c @ self.g,
            "L_world": L_world,
            "x_cm": x_c,
            "q_norm": np.linalg.norm(Y[:, :4], axis=1),
        }
        if self.mu:  # the central field's potential and the momentum about the central body (§9.7)
            out["E_total"] = E_kin + central_potential(self.mu, self.m, I_cm, R, x_c)
            out["L_total"] = self.m * np.cross(x_c, v_c) + L_world
        return out


def central_field(mu: float, m: float, I: np.ndarray, R: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(F (N, world), τ (N·m, body, about the centre of mass)) of the central field μ (m³/s²)
    at the origin on a body of mass m (kg), inertia I (kg·m², body, about the centre of
    mass) and rotation R (body -> world) with its centre of mass at x (m, world): the
    module docstring's formulas, −∂V/∂x and the gravity-gradient torque of MacCullagh's V."""
    r2 = float(x @ x)
    r = np.sqrt(r2)
    Iw_x = R @ (I @ (R.T @ x))
    u = float(x @ Iw_x)
    F = -mu * m * x / (r2 * r) - 1.5 * mu / (r2 * r2 * r) * ((np.trace(I) - 5.0 * u / r2) * x + 2.0 * Iw_x)
    rho = R.T @ x
    return F, 3.0 * mu / (r2 * r2 * r) * cross3(rho, I @ rho)


def central_potential(mu: float, m: float, I: np.ndarray, R: np.ndarray, x: np.ndarray) -> np.ndarray:
    """V (J) of MacCullagh's formula, −μ m/r − μ/(2 r³)(tr I − 3 r̂ᵀ R I Rᵀ r̂), for rotations R
    (n, 3, 3) and positions x (n, 3) (m, world)."""
    r = np.linalg.norm(x, axis=1)
    rho = np.einsum("nji,nj->ni", R, x)  # Rᵀ x
    u = np.einsum("ni,ij,nj->n", rho, I, rho) / r**2
    return -mu * m / r - mu / (2 * r**3) * (np.trace(I) - 3 * u)


def integrate(
    scene: Any,
    grid: np.ndarray,
    method: str = "DOP853",
    rtol: float = 1e-13,
    atol: float = 1e-15,
    inputs: str = "continuous",
) -> Trajectory:
    """Integrate any scene over the communication grid (s) with scipy's ``solve_ivp``,
    restarted at every point (tables switch on grid points); a moving reference point with
    `MotionODE` (extra "x_cm": centre-of-mass positions, m), with rotors
    ``rbcheck.baselines.gyrostat.integrate_gyrostat`` (extra "Omega": rotor rates, rad/s;
    motor torques from the scene's schedules), otherwise ``rbcheck.baselines.rigid_body.integrate_scipy``.
    inputs "continuous": the physical input, an input that varies inside an interval (a
    harmonic) evaluated at every right-hand-side call; "hold": every input held at its mean
    over the interval (what an importer without intermediate update feeds the FMU)."""
    if inputs not in ("continuous", "hold"):
        raise ValueError(f"inputs must be 'continuous' or 'hold', got {inputs!r}")
    if getattr(scene, "rotors", None):  # the gyrostat (docs/theory.md §8): Ω in extra["Omega"]
        return integrate_gyrostat(scene, grid, method, rtol=rtol, atol=atol, inputs=inputs)
    if not moves(scene):
        return integrate_scipy(scene, grid, method, rtol=rtol, atol=atol, inputs=inputs)
    ode = MotionODE(scene)
    y = np.concatenate([scene.q0, scene.w0, scene.x0, scene.v0]).astype(float)
    names = scene.input_names
    varying = scene.inputs_varying_in_step if inputs == "continuous" else []
    held: dict[str, np.ndarray] = {}

    def hold(t0: float, t1: float) -> None:
        if inputs == "hold":
            held.update({n: scene.input_mean(n, t0, t1) for n in names})
        else:  # constants and tables: constant over the interval (they switch on its ends)
            held.update({n: scene.input_at(n, t0) for n in names})
        ode.hold(held)

    def rhs_varying(t: float, y: np.ndarray) -> np.ndarray:
        ode.hold({**held, **{n: scene.input_at(n, t) for n in varying}})
        return ode.rhs(t, y)

    Y, wall = solve_restarted(rhs_varying if varying else ode.rhs, y, grid, hold, method, rtol, atol)
    inv = ode.invariants(Y)
    return Trajectory(
        time=np.asarray(grid, float),
        q=Y[:, :4],
        w_body=Y[:, 4:7],
        wall_time=wall,
        nfev=ode.nfev,
        extra={"invariants": inv, "x_cm": inv["x_cm"], "v_cm": Y[:, 10:13]},
    )
