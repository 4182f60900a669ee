"""scipy baseline of the gyrostat: a body turning about a fixed point with rotors in torque mode (docs/theory.md §8).

Independent of the FMU (nothing from ``modelsrc`` physics or ``fmu``; a scene is read as
data). The equations of docs/theory.md §8.1 written again in numpy, state
y = (q, ω, Ω_1 … Ω_n): q unit quaternion body -> world (scalar first), ω body angular
velocity (rad/s), Ω_k rotor k's spin rate relative to the body about its unit axis g_k
(rad/s, body frame); I the whole body's inertia (rotors included) about the point it turns
about, J_k the rotors' axial inertias (kg·m²), u_k the motor torques (N·m, on the rotor,
the body feels −u_k g_k):

    q̇ = ½ q ⊗ (0, ω)
    (I − Σ J g gᵀ) ω̇ = τ − ω × (I ω + h) − Σ g u,   h = Σ J Ω g
    Ω̇_k = u_k / J_k − g_k·ω̇

τ (body, N·m): τ_body + Rᵀ τ_world − c ω, gravity about a pivot r_cm × (Rᵀ m g) and the
gravity gradient 3 n² ĉ × (I ĉ) (docs/theory.md §4.1, §9.2), as in
``rbcheck.baselines.RigidBodyODE``. Invariants (§8.2): E = ½ ωᵀ I ω + Σ J Ω (g·ω) + ½ Σ J Ω²
and L_world = R (I ω + h).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from .baselines import Trajectory, scene_has, solve_restarted
from .rotation_np import cross3, quat_to_matrix, quat_to_matrix1

__all__ = ["GyrostatODE", "covers", "integrate_gyrostat"]

# Features whose reference point moves: MotionODE's equations, which have no rotors here.
MOVING = ("translation", "moving_pivot")


def covers(scene: Any) -> bool:
    """True when scipy has a reference of the scene: no rotors (rbcheck.baselines,
    rbcheck.baselines_motion), or rotors all in torque mode on a body turning about a fixed
    point (this module)."""
    rotors = getattr(scene, "rotors", None) or {}
    if not rotors:
        return True
    moving = set(getattr(scene, "features", ())) & set(MOVING)
    return not moving and all(getattr(r, "mode", "torque") == "torque" for r in rotors.values())


class GyrostatODE:
    """Right-hand side of the gyrostat (module docstring) with the torque inputs and the
    motor torques held by `hold` between calls.

    Attributes: I (3×3, kg·m², body, about the rotation point: the parallel-axis theorem
    adds m(|r|² 1 − r rᵀ) with gravity, as RigidBodyODE does), G (n×3, the rotor axes as
    rows), Jr (n, kg·m²), names (the rotors, in the scene's order), Ainv = (I − Σ J g gᵀ)⁻¹.
    """

    def __init__(self, scene: Any):
        features = set(getattr(scene, "features", ()))
        moving = sorted(features & set(MOVING))
        if moving:
            raise ValueError(
                f"scene {scene.name}: the gyrostat baseline turns about a fixed point; features {', '.join(moving)} "
                "(a moving reference point) with rotors are not in rbcheck's numpy equations"
            )
        rotors = dict(scene.rotors)
        if not rotors:
            raise ValueError(f"scene {scene.name}: has no rotors; use rbcheck.baselines.integrate_scipy")
        for name, rotor in rotors.items():
            mode = getattr(rotor, "mode", "torque")
            if mode != "torque":
                raise ValueError(
                    f"scene {scene.name}: rotor {name!r} is in mode {mode!r}; "
                    "the gyrostat baseline has torque mode only"
                )
        self.names = list(rotors)
        self.G = np.array([np.asarray(r.axis, dtype=float) / np.linalg.norm(r.axis) for r in rotors.values()])
        self.Jr = np.array([float(r.J) for r in rotors.values()])
        gravity = scene_has(scene, "gravity")
        self.m = float(getattr(scene, "mass", 0.0)) if gravity else 0.0
        self.r = np.asarray(scene.r_cm, dtype=float).reshape(3) if gravity else np.zeros(3)
        self.g = np.asarray(scene.g, dtype=float).reshape(3) if gravity else np.zeros(3)
        self.c = float(getattr(scene, "c_friction", 0.0)) if scene_has(scene, "friction") else 0.0
        self.n = float(getattr(scene, "orbit_rate", 0.0)) if scene_has(scene, "gravity_gradient") else 0.0
        I_cm = np.asarray(scene.inertia, dtype=float).reshape(3, 3)
        self.I = I_cm + self.m * (float(self.r @ self.r) * np.eye(3) - np.outer(self.r, self.r))
        # the rest of the body, I − Σ J g gᵀ (§8.1), is positive definite (the scene reader's rule)
        self.Ainv = np.linalg.inv(self.I - np.einsum("k,ki,kj->ij", self.Jr, self.G, self.G))
        self.nfev = 0
        self.hold(np.zeros(3), np.zeros(3), np.zeros(len(self.names)))

    def hold(self, tau_body: np.ndarray, tau_world: np.ndarray, u: np.ndarray) -> None:
        """Hold τ_body (N·m, body), τ_world (N·m, world) and the motor torques u (N·m, one per
        rotor, in `names` order) until the next call."""
        self.tau_b = np.asarray(tau_body, dtype=float).reshape(3)
        self.tau_w = np.asarray(tau_world, dtype=float).reshape(3)
        self.u = np.asarray(u, dtype=float).reshape(len(self.names))
        self.Gu = self.G.T @ self.u  # Σ g u (body)
        self.u_over_J = self.u / self.Jr
        self.need_R = self.m != 0.0 or self.n != 0.0 or bool(np.any(self.tau_w != 0.0))

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt at y = (q, ω, Ω) (7 + n,); t (s): the orbit's nadir (inputs are held)."""
        self.nfev += 1
        q, w, Om = y[0:4], y[4:7], y[7:]
        tau = self.tau_b - self.c * w
        if self.need_R:
            Rt = quat_to_matrix1(q).T  # of q/|q|: scipy does not keep |q| = 1
            tau = tau + Rt @ self.tau_w
            if self.m:  # τ_g = r_cm × (Rᵀ m g) about the pivot (§4.1)
                tau = tau + cross3(self.r, Rt @ (self.m * self.g))
            if self.n:  # 3 n² ĉ × (I ĉ), ĉ = Rᵀ (−sin n t, 0, cos n t) (§9.2)
                c = Rt @ np.array([-math.sin(self.n * t), 0.0, math.cos(self.n * t)])
                tau = tau + 3.0 * self.n**2 * cross3(c, self.I @ c)
        h = self.G.T @ (self.Jr * Om)
        w_dot = self.Ainv @ (tau - cross3(w, self.I @ w + h) - self.Gu)
        Om_dot = self.u_over_J - self.G @ w_dot
        a, b, c_, d = q
        q_dot = 0.5 * np.array(
            [-b * w[0] - c_ * w[1] - d * w[2], a * w[0] + c_ * w[2] - d * w[1], a * w[1] + d * w[0] - b * w[2],
             a * w[2] + b * w[1] - c_ * w[0]]
        )  # fmt: skip
        return np.concatenate([q_dot, w_dot, Om_dot])

    def invariants(self, Y: np.ndarray) -> dict[str, np.ndarray]:
        """E_kin (J, §8.2), E_total (J, with −m g·(R r_cm) about the pivot), L_body = I ω + h and
        L_world = R L_body (N·m·s) and |q| of states Y (N, 7 + n)."""
        Y = np.atleast_2d(Y)
        R = quat_to_matrix(Y[:, :4])
        w, Om = Y[:, 4:7], Y[:, 7:]
        JOm = Om * self.Jr
        Lb = w @ self.I.T + JOm @ self.G
        E_kin = 0.5 * np.einsum("ni,ij,nj->n", w, self.I, w) + np.einsum("nk,nk->n", JOm, w @ self.G.T)
        E_kin = E_kin + 0.5 * np.einsum("nk,nk->n", JOm, Om)
        E_pot = -self.m * np.einsum("j,nj->n", self.g, R @ self.r)
        return {
            "E_kin": E_kin,
            "E_total": E_kin + E_pot,
            "L_body": Lb,
            "L_world": np.einsum("nij,nj->ni", R, Lb),
            "q_norm": np.linalg.norm(Y[:, :4], axis=1),
        }


def _rotor_torque(scene: Any, name: str, t0: float, t1: float, mean: bool) -> float:
    """Motor torque u_<name> (N·m) of the scene's schedule at t0 (mean over [t0, t1] when
    `mean`); 0 without one (the FMU's start value)."""
    spec = (getattr(scene, "inputs", {}) or {}).get(f"u_{name}")
    if spec is None:
        return 0.0
    v = scene.input_mean(f"u_{name}", t0, t1) if mean else scene.input_at(f"u_{name}", t0)
    return float(np.ravel(v)[0])


def integrate_gyrostat(
    scene: Any,
    grid: np.ndarray,
    method: str = "DOP853",
    rtol: float = 1e-13,
    atol: float = 1e-15,
    inputs: str = "continuous",
    rotor_u: Mapping[str, float] | None = None,
) -> Trajectory:
    """Integrate a gyrostat scene over the communication grid (s) with scipy's ``solve_ivp``,
    restarted at every point as an FMU doStep is. The torque inputs as in
    ``rbcheck.baselines.integrate_scipy`` (inputs "continuous": a harmonic evaluated at every
    right-hand-side call; "hold": its mean over the interval); the motor torques from the
    scene's schedules u_<name> (a table held over an interval, a harmonic evaluated at every
    call with "continuous", every schedule at its mean over the interval with "hold"; 0
    without one) unless `rotor_u` (rotor name -> N·m) holds them constant.
    Trajectory.extra: "Omega" (N, n) rad/s, "rotors" (their names), "invariants".
    Raises ValueError for a scene this baseline does not cover (moving reference point,
    speed-mode rotors, no rotors), an unknown rotor in rotor_u or a bad `inputs`."""
    if inputs not in ("continuous", "hold"):
        raise ValueError(f"inputs must be 'continuous' or 'hold', got {inputs!r}")
    ode = GyrostatODE(scene)
    fixed_u = dict(rotor_u or {})
    unknown = sorted(set(fixed_u) - set(ode.names))
    if unknown:
        raise ValueError(f"rotor_u names {', '.join(unknown)}: not rotors of {scene.name} ({', '.join(ode.names)})")
    y0 = np.concatenate(
        [np.asarray(scene.q0, dtype=float), np.asarray(scene.w0, dtype=float)]
        + [[float(r.Omega0)] for r in scene.rotors.values()]
    )
    in_step = set(getattr(scene, "inputs_varying_in_step", []))
    varying = [n for n in in_step if n in ("tau_body", "tau_world")]
    varying_u = [k for k, n in enumerate(ode.names) if f"u_{n}" in in_step and n not in fixed_u]  # harmonics
    mean = inputs == "hold"
    held: dict[str, np.ndarray] = {}

    def torques(t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
        if mean:
            return scene.input_mean("tau_body", t0, t1), scene.input_mean("tau_world", t0, t1)
        return scene.input_at("tau_body", t0), scene.input_at("tau_world", t0)

    def hold(t0: float, t1: float) -> None:
        u = [fixed_u[n] if n in fixed_u else _rotor_torque(scene, n, t0, t1, mean) for n in ode.names]
        held["u"] = np.array(u, dtype=float)
        ode.hold(*torques(t0, t1), held["u"])

    def rhs_varying(t: float, y: np.ndarray) -> np.ndarray:
        u = held["u"].copy()
        for k in varying_u:
            u[k] = _rotor_torque(scene, ode.names[k], t, t, False)
        ode.hold(scene.input_at("tau_body", t), scene.input_at("tau_world", t), u)
        return ode.rhs(t, y)

    continuous = (varying or varying_u) and not mean
    Y, wall = solve_restarted(rhs_varying if continuous else ode.rhs, y0, grid, hold, method, rtol, atol)
    return Trajectory(
        time=np.asarray(grid, float),
        q=Y[:, :4],
        w_body=Y[:, 4:7],
        wall_time=wall,
        nfev=ode.nfev,
        extra={"Omega": Y[:, 7:], "rotors": list(ode.names), "invariants": ode.invariants(Y)},
    )
