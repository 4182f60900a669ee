"""Baselines and references for the work-precision report (docs/report/report.md).

Independent of the FMU: the equations of motion are written here again, in numpy
(nothing from ``modelsrc`` or ``fmu`` is imported; a scene is read as data only, any
object with the fields of ``modelsrc.scene.Scene``). Used three ways:

* the reference solution where no closed form exists (``sleeping_top``, ``torque_driven``,
  the closed-loop co-simulation): scipy ``solve_ivp`` DOP853 at rtol = 1e-13;
* the scipy baselines of the report (DOP853, Radau, LSODA on a tolerance ladder);
* the Exudyn baselines, through ``rbcheck.exudyn.models.simulate_scene``.

Equations (docs/theory.md §1.2, §2.1, §2.2, §4.1, §4.3), SI units, state
y = (q, ω): q unit quaternion body -> world, scalar first; ω body angular velocity (rad/s)

    q̇ = ½ q ⊗ (0, ω)
    J ω̇ = τ − ω × J ω,   τ = τ_body + Rᵀ τ_world + r_cm × (Rᵀ m g) − c ω

with J the inertia about the rotation point: about the centre of mass for a free body,
about the pivot (parallel-axis theorem, J = I_cm + m(|r|² 1 − r rᵀ)) with gravity.
The quaternion is not projected during the integration (the scipy methods know nothing
of |q| = 1); R is formed from q/|q| so the torques stay those of a rotation.
"""

from __future__ import annotations

import itertools
import math
import time as _time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from ..numerics.rotation_np import quat_conj, quat_to_matrix

__all__ = [
    "SCIPY_METHODS",
    "AttitudePD",
    "OneSampleDelay",
    "RigidBodyODE",
    "Trajectory",
    "closed_loop_scipy",
    "comm_grid",
    "integrate_scipy",
    "run_exudyn",
    "scene_has",
    "table_value",
]

SCIPY_METHODS = ("DOP853", "Radau", "LSODA")
Controller = Callable[[float, Mapping[str, float]], Mapping[str, float]]


def scene_has(scene: Any, feature: str) -> bool:
    """True when the scene (duck-typed) declares `feature` ("gravity", "friction", ...)."""
    if hasattr(scene, "has"):
        return bool(scene.has(feature))
    return feature in getattr(scene, "features", ())


def table_value(value: Any, t: float) -> np.ndarray:
    """Input (N·m) held on [t_k, t_k+1) at time t (s): constant (3,) or rows [t, x, y, z]."""
    v = np.asarray(value, dtype=float)
    if v.ndim == 1:
        return v
    k = int(np.searchsorted(v[:, 0], t, side="right")) - 1
    return v[max(k, 0), 1:]


def comm_grid(scene: Any, stop_time: float, step: float) -> np.ndarray:
    """Communication points 0, step, ..., stop_time plus the switching times of the scene's
    input tables (s), the same points the FMU driver and Exudyn's driver use."""
    if not (math.isfinite(stop_time) and stop_time > 0 and math.isfinite(step) and step > 0):
        raise ValueError(f"stop_time and step must be finite and > 0 (s), got {stop_time}, {step}")
    n = round(stop_time / step)
    if n >= 1 and abs(n * step - stop_time) <= 1e-9 * stop_time:
        pts = [i * step for i in range(n + 1)]
    else:
        pts = list(np.arange(0.0, stop_time, step)) + [stop_time]
    for v in (getattr(scene, "inputs", {}) or {}).values():
        if np.ndim(v) == 2:
            pts += [float(t) for t in np.asarray(v)[:, 0] if 0.0 < t < stop_time]
    pts_a = np.unique(np.asarray(pts, dtype=float))
    keep = np.concatenate([[True], np.diff(pts_a) > 1e-12 * max(1.0, stop_time)])
    return pts_a[keep]


class RigidBodyODE:
    """Right-hand side of Euler's equations and quaternion kinematics for one scene.

    Written with scalar arithmetic (7 states: numpy's per-call overhead would dominate),
    so that the scipy baselines are timed on a fair, lean right-hand side.
    Attributes: J (3×3, kg·m², about the rotation point, body frame), Jinv, m (kg),
    r (m, body, pivot -> centre of mass), g (m/s², world), c (N·m·s/rad), and the held
    inputs tau_body (N·m, body), tau_world (N·m, world), changed between segments;
    n (rad/s): the orbit rate of a scene with features.gravity_gradient (0 without), whose
    torque 3 n² ĉ × (J ĉ) takes the nadir ĉ = Rᵀ (−sin n t, 0, cos n t) at the time t
    (docs/theory.md §9.1, §9.2); held: the rate is prescribed (features.prescribed_rate),
    ω̇ = 0 in place of Euler's equations (§4.4).
    """

    def __init__(self, scene: Any):
        I = np.asarray(scene.inertia, dtype=float).reshape(3, 3)
        gravity = scene_has(scene, "gravity")
        self.m = float(getattr(scene, "mass", 0.0)) if gravity else 0.0
        self.r = np.asarray(scene.r_cm, dtype=float).reshape(3) if gravity else np.zeros(3)
        self.g = np.asarray(scene.g, dtype=float).reshape(3) if gravity else np.zeros(3)
        self.c = float(getattr(scene, "c_friction", 0.0)) if scene_has(scene, "friction") else 0.0
        # parallel-axis theorem (docs/theory.md §3.2): Euler's equations about the pivot (§4.1)
        self.J = I + self.m * (float(self.r @ self.r) * np.eye(3) - np.outer(self.r, self.r))
        self.Jinv = np.linalg.inv(self.J)
        self.tau_body = np.zeros(3)
        self.tau_world = np.zeros(3)
        self.gravity = gravity
        self.n = float(getattr(scene, "orbit_rate", 0.0)) if scene_has(scene, "gravity_gradient") else 0.0
        self.held = scene_has(scene, "prescribed_rate")
        self.nfev = 0

    def set_inputs(self, tau_body: Sequence[float] | None = None, tau_world: Sequence[float] | None = None) -> None:
        """Hold the torque inputs (N·m; body resp. world frame) until the next call."""
        if tau_body is not None:
            self.tau_body = np.asarray(tau_body, dtype=float).reshape(3)
        if tau_world is not None:
            self.tau_world = np.asarray(tau_world, dtype=float).reshape(3)

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt at y = (q0, q1, q2, q3, ω1, ω2, ω3); t (s): the orbit's nadir (inputs are held)."""
        self.nfev += 1
        a, b, c, d, w1, w2, w3 = (float(v) for v in y)
        J, Ji = self._Jt, self._Jit
        # body-frame torque τ (N·m): inputs, friction, gravity
        t1, t2, t3 = self._tb
        t1 -= self.c * w1
        t2 -= self.c * w2
        t3 -= self.c * w3
        if self._need_R:
            # Rᵀ of q/|q| (docs/theory.md §1.1): columns of R are the body axes in world
            s = 1.0 / (a * a + b * b + c * c + d * d)
            r11 = 1 - 2 * s * (c * c + d * d)
            r12 = 2 * s * (b * c - a * d)
            r13 = 2 * s * (b * d + a * c)
            r21 = 2 * s * (b * c + a * d)
            r22 = 1 - 2 * s * (b * b + d * d)
            r23 = 2 * s * (c * d - a * b)
            r31 = 2 * s * (b * d - a * c)
            r32 = 2 * s * (c * d + a * b)
            r33 = 1 - 2 * s * (b * b + c * c)
            fx, fy, fz = self._fw  # world vector: τ_world + (m g) handled separately below
            t1 += r11 * fx + r21 * fy + r31 * fz
            t2 += r12 * fx + r22 * fy + r32 * fz
            t3 += r13 * fx + r23 * fy + r33 * fz
            if self.gravity:  # τ_g = r_cm × (Rᵀ m g)  (§4.1)
                gx, gy, gz = self._mg
                bx = r11 * gx + r21 * gy + r31 * gz
                by = r12 * gx + r22 * gy + r32 * gz
                bz = r13 * gx + r23 * gy + r33 * gz
                rx, ry, rz = self._rt
                t1 += ry * bz - rz * by
                t2 += rz * bx - rx * bz
                t3 += rx * by - ry * bx
            if self.n:  # gravity gradient 3 n² ĉ × (J ĉ), ĉ = Rᵀ c_world(t) (§9.2)
                cx, cz = -math.sin(self.n * t), math.cos(self.n * t)
                c1, c2, c3 = r11 * cx + r31 * cz, r12 * cx + r32 * cz, r13 * cx + r33 * cz
                k = 3.0 * self.n * self.n
                Jc1 = J[0] * c1 + J[1] * c2 + J[2] * c3
                Jc2 = J[3] * c1 + J[4] * c2 + J[5] * c3
                Jc3 = J[6] * c1 + J[7] * c2 + J[8] * c3
                t1 += k * (c2 * Jc3 - c3 * Jc2)
                t2 += k * (c3 * Jc1 - c1 * Jc3)
                t3 += k * (c1 * Jc2 - c2 * Jc1)
        # L = J ω; ω̇ = J⁻¹ (τ − ω × L)  (§2.1)
        L1 = J[0] * w1 + J[1] * w2 + J[2] * w3
        L2 = J[3] * w1 + J[4] * w2 + J[5] * w3
        L3 = J[6] * w1 + J[7] * w2 + J[8] * w3
        e1 = t1 - (w2 * L3 - w3 * L2)
        e2 = t2 - (w3 * L1 - w1 * L3)
        e3 = t3 - (w1 * L2 - w2 * L1)
        if self.held:  # a prescribed rate: the bearings supply whatever holds ω (§4.4)
            e1 = e2 = e3 = 0.0
        # q̇ = ½ q ⊗ (0, ω)  (§1.2)
        return np.array(
            [
                -0.5 * (b * w1 + c * w2 + d * w3),
                0.5 * (a * w1 + c * w3 - d * w2),
                0.5 * (a * w2 + d * w1 - b * w3),
                0.5 * (a * w3 + b * w2 - c * w1),
                Ji[0] * e1 + Ji[1] * e2 + Ji[2] * e3,
                Ji[3] * e1 + Ji[4] * e2 + Ji[5] * e3,
                Ji[6] * e1 + Ji[7] * e2 + Ji[8] * e3,
            ]
        )

    def prepare(self) -> None:
        """Cache the held inputs and parameters as Python floats (call after set_inputs)."""
        self._Jt = tuple(float(v) for v in self.J.ravel())
        self._Jit = tuple(float(v) for v in self.Jinv.ravel())
        self._tb = tuple(float(v) for v in self.tau_body)
        self._fw = tuple(float(v) for v in self.tau_world)
        self._mg = tuple(float(v) for v in self.m * self.g)
        self._rt = tuple(float(v) for v in self.r)
        self._need_R = self.gravity or bool(np.any(self.tau_world != 0.0)) or self.n != 0.0

    def invariants(self, y: np.ndarray) -> dict[str, np.ndarray]:
        """E_kin (J), E_total (J, potential −m g·(R r_cm) about the pivot), L_world (N·m·s,
        about the rotation point) and |q| for states y of shape (n, 7)."""
        y = np.atleast_2d(y)
        R = quat_to_matrix(y[:, :4])
        w = y[:, 4:]
        Lb = w @ self.J.T
        E_kin = 0.5 * np.einsum("ni,ni->n", w, Lb)
        E_pot = -self.m * np.einsum("j,nj->n", self.g, R @ self.r)
        return {
            "E_kin": E_kin,
            "E_total": E_kin + E_pot,
            "L_world": np.einsum("nij,nj->ni", R, Lb),
            "q_norm": np.linalg.norm(y[:, :4], axis=1),
        }


@dataclass
class Trajectory:
    """States at the communication points of one run.

    time (n,) s; q (n, 4) body -> world, scalar first (as integrated, not normalised);
    w_body (n, 3) rad/s; wall_time (s, integration only); nfev (right-hand-side calls,
    scipy) or n_steps (internal steps); extra: anything solver-specific.
    """

    time: np.ndarray
    q: np.ndarray
    w_body: np.ndarray
    wall_time: float
    nfev: int = 0
    n_steps: int = 0
    extra: dict[str, Any] = field(default_factory=dict)


def _scene_inputs_at(scene: Any, t: float) -> tuple[np.ndarray, np.ndarray]:
    if hasattr(scene, "input_at"):  # a Scene: constants, tables, harmonics (modelsrc.scene_inputs)
        return scene.input_at("tau_body", t), scene.input_at("tau_world", t)
    inputs = getattr(scene, "inputs", {}) or {}
    tb = table_value(inputs["tau_body"], t) if "tau_body" in inputs else np.zeros(3)
    tw = table_value(inputs["tau_world"], t) if "tau_world" in inputs else np.zeros(3)
    return tb, tw


def solve_restarted(
    rhs: Callable[[float, np.ndarray], np.ndarray],
    y0: np.ndarray,
    grid: np.ndarray,
    hold: Callable[[float, float], None],
    method: str,
    rtol: float,
    atol: float,
) -> tuple[np.ndarray, float]:
    """One ``solve_ivp`` call of `rhs` per interval [t0, t1] of `grid` (s), restarted at
    every point as an FMU doStep or an Exudyn chunk is, from y0; hold(t0, t1) sets the
    inputs held over the interval before it. Returns the states at the grid points (rows)
    and the wall time (s) of the solve_ivp calls. Raises ValueError for an unknown method
    or non-positive tolerances, RuntimeError when a call fails."""
    if method not in SCIPY_METHODS:
        raise ValueError(f"unknown scipy method {method!r}; use one of {SCIPY_METHODS}")
    if not (rtol > 0 and atol > 0):
        raise ValueError(f"rtol and atol must be > 0, got rtol={rtol}, atol={atol}")
    y, ys, wall = y0, [y0], 0.0
    for t0, t1 in itertools.pairwise(grid):
        hold(float(t0), float(t1))
        tic = _time.perf_counter()
        sol = solve_ivp(rhs, (float(t0), float(t1)), y, method=method, rtol=rtol, atol=atol)
        wall += _time.perf_counter() - tic
        if not sol.success:
            raise RuntimeError(f"solve_ivp {method} (rtol={rtol}) failed on [{t0}, {t1}] s: {sol.message}")
        y = sol.y[:, -1]
        ys.append(y)
    return np.array(ys), wall


def integrate_scipy(
    scene: Any,
    grid: np.ndarray,
    method: str = "DOP853",
    rtol: float = 1e-13,
    atol: float = 1e-15,
    inputs: str = "continuous",
) -> Trajectory:
    """Integrate a scene over the communication grid (s) with scipy's ``solve_ivp``.

    One ``solve_ivp`` call per interval, restarted at every point as an FMU doStep or an
    Exudyn chunk is (the scene's tables switch on grid points, so they are constant over
    an interval). A torque that varies inside an interval (a harmonic, the scene's
    ``inputs_varying_in_step``) is evaluated at every right-hand-side call (inputs
    "continuous") or held at its mean over the interval ("hold"). rtol and atol are passed
    explicitly (atol absolute on every state: q is O(1), ω in rad/s).
    Raises ValueError for an unknown method or non-positive tolerances.
    """
    ode = RigidBodyODE(scene)
    y = np.concatenate([np.asarray(scene.q0, dtype=float), np.asarray(scene.w0, dtype=float)])
    varying = list(getattr(scene, "inputs_varying_in_step", []))

    def hold(t0: float, t1: float) -> None:
        if varying and inputs == "hold":  # the mean over the interval
            ode.set_inputs(*(scene.input_mean(n, t0, t1) for n in ("tau_body", "tau_world")))
        else:
            ode.set_inputs(*_scene_inputs_at(scene, t0))
        ode.prepare()

    def rhs_varying(t: float, y: np.ndarray) -> np.ndarray:
        ode.set_inputs(*(scene.input_at(n, t) for n in ("tau_body", "tau_world")))
        ode.prepare()
        return ode.rhs(t, y)

    continuous = varying and inputs == "continuous"
    Y, wall = solve_restarted(rhs_varying if continuous else ode.rhs, y, grid, hold, method, rtol, atol)
    return Trajectory(
        time=np.asarray(grid, float),
        q=Y[:, :4],
        w_body=Y[:, 4:],
        wall_time=wall,
        nfev=ode.nfev,
        extra={"invariants": ode.invariants(Y)},
    )


def outputs_dict(q: np.ndarray, w: np.ndarray) -> dict[str, float]:
    """The FMU-style output names a controller reads: "q[1]".."q[4]", "w_body[1]".."w_body[3]"."""
    d = {f"q[{k + 1}]": float(q[k]) for k in range(4)}
    d.update({f"w_body[{k + 1}]": float(w[k]) for k in range(3)})
    return d


def _apply(u: Mapping[str, float], tb: np.ndarray, tw: np.ndarray) -> None:
    for key, val in u.items():
        base, _, idx = key.partition("[")
        k = int(idx.rstrip("]")) - 1
        if base == "tau_body":
            tb[k] = float(val)
        elif base == "tau_world":
            tw[k] = float(val)
        else:
            raise KeyError(f"controller returned {key!r}; inputs are tau_body[1..3], tau_world[1..3]")


def closed_loop_scipy(
    scene: Any, controller: Controller, stop_time: float, step: float, rtol: float = 1e-13, atol: float = 1e-15
) -> Trajectory:
    """Reference of a sampled-data loop: the controller is called at t = 0, step, ... with
    the current state (FMU output names) and its torques are held over the interval,
    which DOP853 integrates at rtol/atol (explicit). Same loop as the FMU co-simulation."""
    ode = RigidBodyODE(scene)
    grid = comm_grid(type("G", (), {"inputs": {}})(), stop_time, step)
    y = np.concatenate([np.asarray(scene.q0, dtype=float), np.asarray(scene.w0, dtype=float)])
    tb, tw = np.zeros(3), np.zeros(3)
    ys = [y]
    tic = _time.perf_counter()
    for t0, t1 in itertools.pairwise(grid):
        _apply(controller(float(t0), outputs_dict(y[:4], y[4:])), tb, tw)
        ode.set_inputs(tb, tw)
        ode.prepare()
        sol = solve_ivp(ode.rhs, (float(t0), float(t1)), y, method="DOP853", rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(f"closed-loop reference failed on [{t0}, {t1}] s: {sol.message}")
        y = sol.y[:, -1]
        ys.append(y)
    Y = np.array(ys)
    return Trajectory(
        time=grid,
        q=Y[:, :4],
        w_body=Y[:, 4:],
        wall_time=_time.perf_counter() - tic,
        nfev=ode.nfev,
        extra={"invariants": ode.invariants(Y)},
    )


class AttitudePD:
    """Quaternion-feedback attitude controller (Wie, Weiss & Arapostathis, "Quaternion
    feedback regulator for spacecraft eigenaxis rotations", J. Guid. Control Dyn. 12 (1989)):

        e = q_target* ⊗ q  (error rotation),  τ_body = −kp sign(e0) e_vec − kd ω_body

    kp (N·m per unit quaternion vector), kd (N·m·s/rad); plus a constant world-frame
    disturbance torque tau_world (N·m). Reads "q[1..4]", "w_body[1..3]"; returns
    "tau_body[1..3]" and "tau_world[1..3]". Counts its calls and the time spent in it.
    """

    def __init__(self, q_target: Sequence[float], kp: float, kd: float, tau_world: Sequence[float] = (0.0, 0.0, 0.0)):
        qt = np.asarray(q_target, dtype=float).reshape(4)
        n = float(np.linalg.norm(qt))
        if not (math.isfinite(n) and n > 0):
            raise ValueError(f"q_target must be a non-zero finite quaternion, got {q_target!r}")
        if not (kp > 0 and kd > 0):
            raise ValueError(f"kp and kd must be > 0, got kp={kp}, kd={kd}")
        self.qt_conj = quat_conj(qt / n)
        self._qt = tuple(float(v) for v in self.qt_conj)
        self.kp, self.kd = float(kp), float(kd)
        self.tau_world = {f"tau_world[{k + 1}]": float(v) for k, v in enumerate(tau_world)}
        self.calls = 0
        self.time_spent = 0.0

    def __call__(self, t: float, out: Mapping[str, float]) -> dict[str, float]:
        tic = _time.perf_counter()
        # e = q_target* ⊗ q, written out (scalar code: this runs once per Δ in the loop)
        w, x, y, z = out["q[1]"], out["q[2]"], out["q[3]"], out["q[4]"]
        tw, tx, ty, tz = self._qt
        a = tw * w - tx * x - ty * y - tz * z
        b = tw * x + tx * w + ty * z - tz * y
        c = tw * y - tx * z + ty * w + tz * x
        d = tw * z + tx * y - ty * x + tz * w
        s = -self.kp if a >= 0.0 else self.kp  # shorter way round (sign(e0))
        u = {
            "tau_body[1]": s * b - self.kd * out["w_body[1]"],
            "tau_body[2]": s * c - self.kd * out["w_body[2]"],
            "tau_body[3]": s * d - self.kd * out["w_body[3]"],
        }
        u.update(self.tau_world)
        self.calls += 1
        self.time_spent += _time.perf_counter() - tic
        return u


class OneSampleDelay:
    """A sampled-data controller as a Jacobi-stepping master (ECOS, libcosim) closes it: the torques
    it returns at sample k are the law's at sample k − 1, law(x_{k−1}), and at k = 0 the law's at
    the start, law(x_0) (the controller's outputs after initialisation). Wraps any controller
    called as controller(t, outputs); counts nothing of its own (the law keeps its counters)."""

    def __init__(self, law: Controller):
        self.law = law
        self._held: Mapping[str, float] | None = None

    def __call__(self, t: float, out: Mapping[str, float]) -> Mapping[str, float]:
        now = self.law(t, out)
        held = now if self._held is None else self._held
        self._held = now
        return held


def run_exudyn(
    scene: Any,
    grid_step: float,
    stop_time: float,
    solver: str,
    h: float | None = None,
    tol: float = 1e-10,
    input_fn: Controller | None = None,
) -> Trajectory:
    """One Exudyn run (``rbcheck.exudyn.models.simulate_scene``) as a Trajectory.

    grid_step: communication step (s); h: internal step (s; DOPRI5: maximum step); tol:
    DOPRI5's rtol = atol. Gravity scenes use the "pivot" model with the explicit solvers
    and the "joint" model (spherical joint) with the implicit ones; a moving reference
    point the models of ``rbcheck.exudyn.motion`` (extra "x_cm", m).
    """
    from ..exudyn.motion import simulate  # imported here: exudyn is heavy to load

    res = simulate(
        scene,
        stop_time=stop_time,
        step=grid_step,
        solver=solver,
        h=grid_step if h is None else h,
        tol=tol,
        input_fn=input_fn,
    )
    extra = {k: res[k] for k in ("E_kin", "E_total", "L_world", "L_body", "model", "x_cm", "cpu_time") if k in res}
    return Trajectory(
        time=res["time"],
        q=res["q"],
        w_body=res["w_body"],
        wall_time=float(res["wall_time"]),
        n_steps=int(res["n_steps"]),
        extra=extra,
    )
