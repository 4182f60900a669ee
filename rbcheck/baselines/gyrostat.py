"""scipy baseline of the gyrostat: a body with rotors in torque or speed mode (docs/theory.md §8).

Independent of the FMU (nothing from ``modelsrc`` physics or ``fmu``; a scene is read as
data). The equations of docs/theory.md §8.1 written again in numpy, state
y = (q, ω, Ω_1 … Ω_n): q unit quaternion body -> world (scalar first), ω body angular
velocity (rad/s), Ω_k rotor k's spin rate relative to the body about its unit axis g_k
(rad/s, body frame); I the whole body's inertia (rotors included) about the point it turns
about, J_k the rotors' axial inertias (kg·m²), u_k the motor torques (N·m, on the rotor,
the body feels −u_k g_k):

    q̇ = ½ q ⊗ (0, ω)
    (I − Σ_T J g gᵀ) ω̇ = τ − ω × (I ω + h) − Σ_T g u − Σ_S J Ω̇ g,   h = Σ J Ω g
    Ω̇_k = u_k / J_k − g_k·ω̇   (torque mode, the set T)

A speed-mode rotor (the set S, §8.5) has no state: its Ω(t) and Ω̇(t) are read from the
scene's schedules as functions of time (held at their means over an interval with
inputs "hold", as an importer without intermediate update feeds the FMU). A body with
``translation`` turns about its centre of mass and adds y = (…, x, v) (m, m/s, world),
M v̇ = R Σ F + M g; a propeller (§8.6) at r (body) adds the thrust F = k_f Ω² g and the
torque r × F − k_m Ω|Ω| g.

τ (body, N·m): τ_body + Rᵀ τ_world − c ω, gravity about a pivot r_cm × (Rᵀ m g) and the
gravity gradient 3 n² ĉ × (I ĉ) (docs/theory.md §4.1, §9.2), as in
``rbcheck.baselines.rigid_body.RigidBodyODE``. Invariants (§8.2): E = ½ ωᵀ I ω + Σ J Ω (g·ω) + ½ Σ J Ω²
and L_world = R (I ω + h).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..numerics.rotation_np import cross3, quat_to_matrix, quat_to_matrix1
from .rigid_body import Trajectory, scene_has, solve_restarted

__all__ = ["GyrostatODE", "covers", "integrate_gyrostat"]


def covers(scene: Any) -> bool:
    """True when scipy has a reference of the scene: no rotors (rbcheck.baselines.rigid_body,
    rbcheck.baselines.motion), or rotors (torque or speed mode; not command mode) on a body turning about a
    fixed point or free (translation, no force points, no central field: this module),
    speed-mode rates not given by a table."""
    rotors = getattr(scene, "rotors", None) or {}
    if not rotors:
        return True
    features = set(getattr(scene, "features", ()))
    if "moving_pivot" in features or ("translation" in features and getattr(scene, "force_points", None)):
        return False
    if "central_gravity" in features:  # this module has no central field (rbcheck.baselines.motion has)
        return False
    if "prescribed_rate" in features:  # nor a held hub rate (§4.4)
        return False
    if any(getattr(r, "mode", "torque") not in ("torque", "speed") for r in rotors.values()):
        return False  # command mode (docs/theory.md §8.8): its lag is not in this module's equations
    tables = [n for n, r in rotors.items() if r.speed and np.ndim(scene.inputs.get(f"Omega_{n}", 0.0)) == 2]
    return not tables


class GyrostatODE:
    """Right-hand side of the gyrostat (module docstring) with the torque inputs and the
    motor torques held by `hold` between calls.

    Attributes: I (3×3, kg·m², body, about the rotation point: the parallel-axis theorem
    adds m(|r|² 1 − r rᵀ) with gravity, as RigidBodyODE does), G (n×3, the rotor axes as
    rows), Jr (n, kg·m²), names (the rotors, in the scene's order), Ainv = (I − Σ J g gᵀ)⁻¹.
    """

    def __init__(self, scene: Any):
        features = set(getattr(scene, "features", ()))
        if "moving_pivot" in features:
            raise ValueError(
                f"scene {scene.name}: a moving pivot with rotors is not in rbcheck's numpy equations "
                "(the gyrostat baseline turns about a fixed point or the free centre of mass)"
            )
        rotors = dict(scene.rotors)
        if not rotors:
            raise ValueError(f"scene {scene.name}: has no rotors; use rbcheck.baselines.rigid_body.integrate_scipy")
        self.translation = "translation" in features
        if self.translation and getattr(scene, "force_points", None):
            raise ValueError(f"scene {scene.name}: force points on a free body with rotors are not in this baseline")
        self.names = list(rotors)
        self.speed = np.array([bool(getattr(r, "speed", False)) for r in rotors.values()])
        self.G = np.array([np.asarray(r.axis, dtype=float) / np.linalg.norm(r.axis) for r in rotors.values()])
        self.Jr = np.array([float(r.J) for r in rotors.values()])
        props = [(k, r) for k, r in enumerate(rotors.values()) if getattr(r, "position", None) is not None]
        self.prop_idx = np.array([k for k, _ in props], dtype=int)
        self.prop_r = np.array([np.asarray(r.position, dtype=float) for _, r in props]).reshape(-1, 3)
        self.prop_kf = np.array([float(r.k_f) for _, r in props])
        self.prop_km = np.array([float(r.k_m) for _, r in props])
        gravity = scene_has(scene, "gravity")
        self.M = float(getattr(scene, "mass", 1.0))
        # gravity about a pivot (a top with wheels) turns it; on a free body it acts at the centre of mass
        self.m = float(getattr(scene, "mass", 0.0)) if gravity and not self.translation else 0.0
        self.r = np.asarray(scene.r_cm, dtype=float).reshape(3) if self.m else np.zeros(3)
        self.g = np.asarray(scene.g, dtype=float).reshape(3) if gravity else np.zeros(3)
        self.c = float(getattr(scene, "c_friction", 0.0)) if scene_has(scene, "friction") else 0.0
        self.n = float(getattr(scene, "orbit_rate", 0.0)) if scene_has(scene, "gravity_gradient") else 0.0
        I_cm = np.asarray(scene.inertia, dtype=float).reshape(3, 3)
        self.I = I_cm + self.m * (float(self.r @ self.r) * np.eye(3) - np.outer(self.r, self.r))
        # the rest of the body, I − Σ_T J g gᵀ (§8.1, §8.5: a speed-mode rotor's J stays), is
        # positive definite (the scene reader's rule)
        T = ~self.speed
        self.Ainv = np.linalg.inv(self.I - np.einsum("k,ki,kj->ij", self.Jr[T], self.G[T], self.G[T]))
        self.nfev = 0
        self.hold(np.zeros(3), np.zeros(3), np.zeros(int(T.sum())))
        self.hold_speeds(np.zeros(int(self.speed.sum())), np.zeros(int(self.speed.sum())))

    def hold(self, tau_body: np.ndarray, tau_world: np.ndarray, u: np.ndarray) -> None:
        """Hold τ_body (N·m, body), τ_world (N·m, world) and the motor torques u (N·m, one per
        torque-mode rotor, in `names` order) until the next call."""
        T = ~self.speed
        self.tau_b = np.asarray(tau_body, dtype=float).reshape(3)
        self.tau_w = np.asarray(tau_world, dtype=float).reshape(3)
        self.u = np.asarray(u, dtype=float).reshape(int(T.sum()))
        self.Gu = self.G[T].T @ self.u  # Σ_T g u (body)
        self.u_over_J = self.u / self.Jr[T]
        self.need_R = self.m != 0.0 or self.n != 0.0 or bool(np.any(self.tau_w != 0.0)) or self.translation

    def hold_speeds(self, Omega: np.ndarray, Omega_dot: np.ndarray) -> None:
        """Hold the speed-mode rotors' rates Ω (rad/s) and their derivatives Ω̇ (rad/s², one per
        speed-mode rotor, in `names` order) until the next call; their reaction −Σ_S J Ω̇ g and
        their propellers' thrust and torque (§8.5, §8.6) follow."""
        S = self.speed
        self.Om_S = np.asarray(Omega, dtype=float).reshape(int(S.sum()))
        self.JOmdot_S = self.G[S].T @ (self.Jr[S] * np.asarray(Omega_dot, dtype=float).reshape(int(S.sum())))
        Om = np.zeros(len(self.names))
        Om[S] = self.Om_S
        self.F_prop = np.zeros(3)
        self.tau_prop = np.zeros(3)
        for j, k in enumerate(self.prop_idx):  # only speed-mode rotors are propellers (the scene reader's rule)
            f = self.prop_kf[j] * Om[k] ** 2 * self.G[k]
            self.F_prop = self.F_prop + f
            self.tau_prop = self.tau_prop + cross3(self.prop_r[j], f) - self.prop_km[j] * Om[k] * abs(Om[k]) * self.G[k]

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt at y = (q, ω, Ω_T, [x, v]) (7 + n_T [+ 6],); t (s): the orbit's nadir (inputs
        are held)."""
        self.nfev += 1
        T = ~self.speed
        nT = int(T.sum())
        q, w, Om_T = y[0:4], y[4:7], y[7 : 7 + nT]
        tau = self.tau_b - self.c * w + self.tau_prop
        Rt = None
        if self.need_R:
            Rt = quat_to_matrix1(q).T  # of q/|q|: scipy does not keep |q| = 1
            tau = tau + Rt @ self.tau_w
            if self.m:  # τ_g = r_cm × (Rᵀ m g) about the pivot (§4.1)
                tau = tau + cross3(self.r, Rt @ (self.m * self.g))
            if self.n:  # 3 n² ĉ × (I ĉ), ĉ = Rᵀ (−sin n t, 0, cos n t) (§9.2)
                c = Rt @ np.array([-math.sin(self.n * t), 0.0, math.cos(self.n * t)])
                tau = tau + 3.0 * self.n**2 * cross3(c, self.I @ c)
        h = self.G[T].T @ (self.Jr[T] * Om_T) + self.G[self.speed].T @ (self.Jr[self.speed] * self.Om_S)
        w_dot = self.Ainv @ (tau - cross3(w, self.I @ w + h) - self.Gu - self.JOmdot_S)
        Om_dot = self.u_over_J - self.G[T] @ w_dot
        a, b, c_, d = q
        q_dot = 0.5 * np.array(
            [-b * w[0] - c_ * w[1] - d * w[2], a * w[0] + c_ * w[2] - d * w[1], a * w[1] + d * w[0] - b * w[2],
             a * w[2] + b * w[1] - c_ * w[0]]
        )  # fmt: skip
        if not self.translation:
            return np.concatenate([q_dot, w_dot, Om_dot])
        assert Rt is not None  # need_R is set with translation
        v = y[7 + nT + 3 : 7 + nT + 6]
        return np.concatenate([q_dot, w_dot, Om_dot, v, Rt.T @ self.F_prop / self.M + self.g])

    def invariants(self, Y: np.ndarray, Om: np.ndarray) -> dict[str, np.ndarray]:
        """E_kin (J, §8.2; with translation + ½ M v²), E_total (J, with −m g·(R r_cm) about the
        pivot, −M g·x in free flight), L_body = I ω + h and L_world = R L_body (N·m·s, about
        the reference point) and |q| of states Y (N, ·) with every rotor's rates Om (N, n)."""
        Y = np.atleast_2d(Y)
        R = quat_to_matrix(Y[:, :4])
        w = Y[:, 4:7]
        JOm = Om * self.Jr
        Lb = w @ self.I.T + JOm @ self.G
        E_kin = 0.5 * np.einsum("ni,ij,nj->n", w, self.I, w) + np.einsum("nk,nk->n", JOm, w @ self.G.T)
        E_kin = E_kin + 0.5 * np.einsum("nk,nk->n", JOm, Om)
        E_pot = -self.m * np.einsum("j,nj->n", self.g, R @ self.r)
        if self.translation:
            x, v = Y[:, -6:-3], Y[:, -3:]
            E_kin = E_kin + 0.5 * self.M * np.einsum("ni,ni->n", v, v)
            E_pot = -self.M * (x @ self.g)
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
    ``rbcheck.baselines.rigid_body.integrate_scipy`` (inputs "continuous": a harmonic evaluated at every
    right-hand-side call; "hold": its mean over the interval); the motor torques from the
    scene's schedules u_<name> (a table held over an interval, a harmonic evaluated at every
    call with "continuous", every schedule at its mean over the interval with "hold"; 0
    without one) unless `rotor_u` (rotor name -> N·m) holds them constant; a speed-mode
    rotor's Ω and Ω̇ from the schedules Omega_<name>, Omega_dot_<name> in the same way.
    Trajectory.extra: "Omega" (N, n) rad/s (a speed-mode rotor's: its schedule at the
    points), "rotors" (their names), "invariants", with translation "x_cm" (N, 3) m.
    Raises ValueError for a scene this baseline does not cover (moving pivot, force points
    on a free body, no rotors), an unknown rotor in rotor_u or a bad `inputs`."""
    if inputs not in ("continuous", "hold"):
        raise ValueError(f"inputs must be 'continuous' or 'hold', got {inputs!r}")
    ode = GyrostatODE(scene)
    fixed_u = dict(rotor_u or {})
    torque_names = [n for n, sp in zip(ode.names, ode.speed) if not sp]
    speed_names = [n for n, sp in zip(ode.names, ode.speed) if sp]
    unknown = sorted(set(fixed_u) - set(torque_names))
    if unknown:
        raise ValueError(
            f"rotor_u names {', '.join(unknown)}: not torque-mode rotors of {scene.name} ({', '.join(torque_names)})"
        )
    y0 = np.concatenate(
        [np.asarray(scene.q0, dtype=float), np.asarray(scene.w0, dtype=float)]
        + [[float(scene.rotors[n].Omega0)] for n in torque_names]
        + ([np.asarray(scene.x0, dtype=float), np.asarray(scene.v0, dtype=float)] if ode.translation else [])
    )
    in_step = set(getattr(scene, "inputs_varying_in_step", []))
    varying = [n for n in in_step if n in ("tau_body", "tau_world")]
    varying_u = [k for k, n in enumerate(torque_names) if f"u_{n}" in in_step and n not in fixed_u]  # harmonics
    varying_s = any(f"Omega_{n}" in in_step for n in speed_names)
    mean = inputs == "hold"
    held: dict[str, np.ndarray] = {}

    def speeds(t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
        """(Ω, Ω̇) of the speed-mode rotors: at t0, or their means over [t0, t1] with "hold"."""
        get = (lambda k: scene.input_mean(k, t0, t1)) if mean else (lambda k: scene.input_at(k, t0))
        return tuple(
            np.array([float(np.ravel(get(f"{v}_{n}"))[0]) for n in speed_names]) for v in ("Omega", "Omega_dot")
        )  # type: ignore[return-value]

    def torques(t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
        if mean:
            return scene.input_mean("tau_body", t0, t1), scene.input_mean("tau_world", t0, t1)
        return scene.input_at("tau_body", t0), scene.input_at("tau_world", t0)

    def hold(t0: float, t1: float) -> None:
        u = [fixed_u[n] if n in fixed_u else _rotor_torque(scene, n, t0, t1, mean) for n in torque_names]
        held["u"] = np.array(u, dtype=float)
        ode.hold(*torques(t0, t1), held["u"])
        ode.hold_speeds(*speeds(t0, t1))

    def rhs_varying(t: float, y: np.ndarray) -> np.ndarray:
        u = held["u"].copy()
        for k in varying_u:
            u[k] = _rotor_torque(scene, torque_names[k], t, t, False)
        ode.hold(scene.input_at("tau_body", t), scene.input_at("tau_world", t), u)
        if varying_s:
            ode.hold_speeds(*speeds(t, t))
        return ode.rhs(t, y)

    continuous = (varying or varying_u or varying_s) and not mean
    Y, wall = solve_restarted(rhs_varying if continuous else ode.rhs, y0, grid, hold, method, rtol, atol)
    nT = len(torque_names)
    Om = np.zeros((len(grid), len(ode.names)))
    Om[:, ~ode.speed] = Y[:, 7 : 7 + nT]
    for n in speed_names:
        Om[:, ode.names.index(n)] = [float(np.ravel(scene.input_at(f"Omega_{n}", float(t)))[0]) for t in grid]
    extra = {"Omega": Om, "rotors": list(ode.names), "invariants": ode.invariants(Y, Om)}
    if ode.translation:
        extra["x_cm"] = Y[:, -6:-3]
    return Trajectory(time=np.asarray(grid, float), q=Y[:, :4], w_body=Y[:, 4:7], wall_time=wall, nfev=ode.nfev,
                      extra=extra)  # fmt: skip
