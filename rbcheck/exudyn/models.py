"""Exudyn multibody models of the project's scenes: an independent reference.

Nothing here uses the FMU's equations (``modelsrc.rigid_body``, ``modelsrc.model``,
``modelsrc.quaternion``, ``modelsrc.inertia``, ``fmu``): the equations of motion are
Exudyn's (a rigid body on a rigid-body node, joints, loads, connectors), solved by
Exudyn's own time integrators. A scene is only read as data (any object with the
fields of ``modelsrc.scene.Scene``: inertia, mass, r_cm, g, c_friction, w0, q0,
inputs, stop_time, step, h_max, features / ``has``).

Conventions (as in the FMU and ``rbcheck.numerics.rotation_np``): SI units; quaternions are
scalar first (w, x, y, z) and rotate body -> world; ``w_body`` is the angular velocity
in body axes; world frame = Exudyn's global frame, the pivot at its origin.

Models (``simulate_scene(model=...)``):

* ``"free"`` (scenes without gravity): an ``ObjectRigidBody`` on a rigid-body node at
  the centre of mass; no constraint, no gravity.
* ``"joint"`` (gravity scenes, implicit solvers): node at the centre of mass, a
  ``SphericalJoint`` to ground at the pivot and the weight as a mass-proportional body
  load (``LoadMassProportional`` on a ``MarkerBodyMass``). Exudyn's explicit solvers
  cannot treat joints, so this model needs ``TrapezoidalIndex2`` or ``GeneralizedAlpha``.
* ``"pivot"`` (gravity scenes, explicit solvers): node at the pivot, its 3 translations
  fixed by ``CoordinateConstraint`` s to ground (the explicit solvers eliminate such
  ground constraints), the inertia about the pivot from Exudyn's
  ``RigidBodyInertia(...).Translated(r_cm)`` and the weight a ``LoadForceVector`` m g
  (world) on a ``MarkerBodyPosition`` at r_cm, so Exudyn forms the gravity torque.
  The body is declared with its centre of mass at the node: with a non-zero
  ``centerOfMass`` the explicit solvers' constraint elimination drops the
  translation/rotation coupling of the mass matrix and the weight has no effect at
  all (measured with Exudyn 1.13.6: the top does not move); with the translations
  locked the COM offset enters only through the pivot inertia and the weight's point
  of application, which is exact.

Friction (torque -c ω, body frame) is an ``ObjectConnectorRigidBodySpringDamper``
between ground and the body with zero stiffness and rotational damping c·1 (isotropic,
so the frame in which Exudyn measures the relative angular velocity does not matter);
``friction="user"`` uses a body-fixed ``LoadTorqueVector`` with a load user function
instead. Torque inputs are ``LoadTorqueVector`` s, ``bodyFixed=True`` for tau_body
(body frame) and ``False`` for tau_world (world frame), held constant over each
communication step and updated between steps (co-simulation: one solver object is
initialised once, then ``SolveSteps`` runs each communication interval; measured
bit-identical to one uninterrupted ``SolveDynamic`` run for the explicit solvers, and
within 2e-11 (trapezoidal) / 2e-10 (generalized-α) rad/s at ω = 150 rad/s for the
implicit ones, which restart their Newton iteration at every interval).
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import exudyn as exu
import numpy as np
from exudyn import itemInterface as ii
from exudyn import rigidBodyUtilities as rbu

from ..numerics.rotation_np import matrix_to_quat

__all__ = [
    "EXPLICIT_SOLVERS",
    "IMPLICIT_SOLVERS",
    "build_exudyn_model",
    "comm_times",
    "default_model",
    "exudyn_inertia",
    "exudyn_inertia_cuboid",
    "exudyn_inertia_cylinder",
    "exudyn_inertia_disc",
    "exudyn_inertia_point_masses",
    "exudyn_inertia_rotated",
    "exudyn_inertia_sphere",
    "exudyn_inertia_translated",
    "exudyn_settings",
    "inertia6",
    "rotation_vector",
    "simulate_scene",
]

OVT = exu.OutputVariableType
EXPLICIT_SOLVERS = ("RK44", "RK67", "DOPRI5")
IMPLICIT_SOLVERS = ("TrapezoidalIndex2", "GeneralizedAlpha")
NODE_TYPES = ("RotVecLG", "EulerParameters")
InputFunction = Callable[[float, Mapping[str, float]], Mapping[str, float]]


# ----------------------------------------------------------------------------------
# scene access (duck-typed: a modelsrc.scene.Scene or anything with its fields)
# ----------------------------------------------------------------------------------
def _has(scene: Any, feature: str) -> bool:
    if hasattr(scene, "has"):
        return bool(scene.has(feature))
    return feature in getattr(scene, "features", ())


def inertia6(J: np.ndarray) -> list[float]:
    """Exudyn's 6-vector [Jxx, Jyy, Jzz, Jyz, Jxz, Jxy] of a 3×3 tensor."""
    return [float(x) for x in rbu.InertiaTensor2Inertia6D(np.asarray(J, dtype=float))]


def rotation_vector(q: np.ndarray) -> np.ndarray:
    """Rotation vector φ n (rad) of the unit quaternion q = (cos φ/2, sin φ/2 n)."""
    v = np.asarray(q[1:], dtype=float)
    s = float(np.linalg.norm(v))
    if s == 0.0:
        return np.zeros(3)
    return 2.0 * math.atan2(s, float(q[0])) * v / s


def _table_value(value: np.ndarray, t: float) -> np.ndarray:
    """Input value (N·m) held on [t_k, t_k+1) at time t: constant (3,) or table rows [t,x,y,z]."""
    v = np.asarray(value, dtype=float)
    if v.ndim == 1:
        return v
    k = int(np.searchsorted(v[:, 0], t, side="right")) - 1
    return v[max(k, 0), 1:]


def comm_times(stop_time: float, step: float, switch_times: Sequence[float]) -> np.ndarray:
    """Communication points 0, H, 2H, ..., stop_time plus input-table switching times."""
    n = round(stop_time / step)
    if n >= 1 and abs(n * step - stop_time) <= 1e-9 * stop_time:
        pts = [i * step for i in range(n + 1)]
    else:
        pts = list(np.arange(0.0, stop_time, step)) + [stop_time]
    pts += [t for t in switch_times if 0.0 < t < stop_time]
    pts = np.unique(np.asarray(pts, dtype=float))
    keep = np.concatenate([[True], np.diff(pts) > 1e-12 * max(1.0, stop_time)])
    return pts[keep]


def default_model(scene: Any, solver: str) -> str:
    """Model used by default: "free" without gravity, else "pivot" (explicit) / "joint" (implicit)."""
    if not _has(scene, "gravity"):
        return "free"
    return "pivot" if solver in EXPLICIT_SOLVERS else "joint"


# ----------------------------------------------------------------------------------
# model assembly
# ----------------------------------------------------------------------------------
class _Model:
    """An assembled Exudyn system of one scene and the handles needed while stepping."""

    def __init__(self, scene: Any, model: str, node_type: str, friction: str, varying: Sequence[str] = ()):
        self.sc = scene
        self.model = model
        self.SC = exu.SystemContainer()
        mbs = self.mbs = self.SC.AddSystem()
        I_cm = np.asarray(scene.inertia, dtype=float)
        q0 = np.asarray(scene.q0, dtype=float)
        w0 = np.asarray(scene.w0, dtype=float)
        gravity = _has(scene, "gravity")
        self.m = float(scene.mass)
        self.r_cm = np.asarray(scene.r_cm, dtype=float) if gravity else np.zeros(3)
        self.g = np.asarray(scene.g, dtype=float) if gravity else np.zeros(3)
        self.I_cm = I_cm
        ground = mbs.AddObject(ii.ObjectGround())

        R0 = rbu.EulerParameters2RotationMatrix(q0)  # body -> world
        if model == "pivot":
            pos0, vel0 = np.zeros(3), np.zeros(3)
        else:  # node at the centre of mass; the pivot (gravity scenes) at the world origin
            pos0 = R0 @ self.r_cm
            vel0 = R0 @ np.cross(w0, self.r_cm)
        if node_type == "RotVecLG":
            node = ii.NodeRigidBodyRotVecLG(
                referenceCoordinates=list(pos0) + list(rotation_vector(q0)), initialVelocities=list(vel0) + list(w0)
            )  # ω in body axes
        else:
            ep_t = rbu.AngularVelocity2EulerParameters_t(R0 @ w0, q0)  # Exudyn wants world ω here
            node = ii.NodeRigidBodyEP(
                referenceCoordinates=list(pos0) + list(q0), initialVelocities=list(vel0) + list(ep_t)
            )
        n = self.node = mbs.AddNode(node)

        if model == "pivot":
            # inertia about the pivot from Exudyn's own parallel-axis shift
            J = rbu.RigidBodyInertia(mass=self.m, inertiaTensor=I_cm).Translated(self.r_cm).Inertia()
            body = mbs.AddObject(ii.ObjectRigidBody(mass=self.m, inertia=inertia6(J), nodeNumber=n))
            gnode = mbs.AddNode(ii.NodePointGround())
            for k in range(3):
                m0 = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=gnode, coordinate=k))
                m1 = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=n, coordinate=k))
                mbs.AddObject(ii.CoordinateConstraint(markerNumbers=[m0, m1]))
            if gravity:
                mcm = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=body, localPosition=list(self.r_cm)))
                mbs.AddLoad(ii.LoadForceVector(markerNumber=mcm, loadVector=list(self.m * self.g)))
        else:
            body = mbs.AddObject(ii.ObjectRigidBody(mass=self.m, inertia=inertia6(I_cm), nodeNumber=n))
            if model == "joint":
                m0 = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
                m1 = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=body, localPosition=list(-self.r_cm)))
                mbs.AddObject(ii.SphericalJoint(markerNumbers=[m0, m1]))
                mmass = mbs.AddMarker(ii.MarkerBodyMass(bodyNumber=body))
                mbs.AddLoad(ii.LoadMassProportional(markerNumber=mmass, loadVector=list(self.g)))
        self.body = body
        mrigid = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=body, localPosition=[0.0, 0.0, 0.0]))

        c = float(getattr(scene, "c_friction", 0.0)) if _has(scene, "friction") else 0.0
        if _has(scene, "friction"):
            if friction == "connector":
                mg = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
                mbs.AddObject(
                    ii.ObjectConnectorRigidBodySpringDamper(
                        markerNumbers=[mg, mrigid],
                        stiffness=np.zeros((6, 6)),
                        damping=np.diag([0.0, 0.0, 0.0, c, c, c]),
                    )
                )
            elif friction == "user":

                def friction_torque(mbs_, t, load_vector, _n=n, _c=c):
                    w = mbs_.GetNodeOutput(_n, OVT.AngularVelocityLocal)
                    return [-_c * w[0], -_c * w[1], -_c * w[2]]

                mbs.AddLoad(
                    ii.LoadTorqueVector(markerNumber=mrigid, bodyFixed=True, loadVectorUserFunction=friction_torque)
                )
            else:
                raise ValueError(f"friction must be 'connector' or 'user', got {friction!r}")

        self.loads: dict[str, Any] = {}
        self.varying = tuple(varying)  # torques given as functions of time (continuous inputs)
        for feat, name, fixed in (("torque_body", "tau_body", True), ("torque_world", "tau_world", False)):
            if _has(scene, feat) and name in self.varying:

                def torque_of_time(mbs_, t, load_vector, _name=name):
                    return [float(x) for x in scene.input_at(_name, t)]

                self.loads[name] = mbs.AddLoad(
                    ii.LoadTorqueVector(markerNumber=mrigid, bodyFixed=fixed, loadVectorUserFunction=torque_of_time)
                )
            elif _has(scene, feat):
                self.loads[name] = mbs.AddLoad(
                    ii.LoadTorqueVector(markerNumber=mrigid, bodyFixed=fixed, loadVector=[0.0, 0.0, 0.0])
                )
        mbs.Assemble()
        self.q_prev = q0.copy()

    def set_torque(self, name: str, value: Sequence[float]) -> None:
        self.mbs.SetLoadParameter(self.loads[name], "loadVector", [float(x) for x in value])

    def outputs(self) -> dict[str, np.ndarray]:
        """Current outputs (SI, frames as named) from Exudyn's node outputs."""
        mbs, n = self.mbs, self.node
        R = np.asarray(mbs.GetNodeOutput(n, OVT.RotationMatrix), dtype=float).reshape(3, 3)
        w_b = np.asarray(mbs.GetNodeOutput(n, OVT.AngularVelocityLocal), dtype=float)
        w_w = np.asarray(mbs.GetNodeOutput(n, OVT.AngularVelocity), dtype=float)
        q = matrix_to_quat(R)
        if float(q @ self.q_prev) < 0.0:  # sign continuity
            q = -q
        self.q_prev = q
        if self.model == "pivot":
            p = R @ self.r_cm  # pivot -> centre of mass, world
            v = R @ np.cross(w_b, self.r_cm)  # centre-of-mass velocity, world
        elif self.model == "joint":
            p = np.asarray(mbs.GetNodeOutput(n, OVT.Position), dtype=float)
            v = np.asarray(mbs.GetNodeOutput(n, OVT.Velocity), dtype=float)
        else:
            p, v = np.zeros(3), np.zeros(3)  # about the centre of mass; translation unused
        E_kin = 0.5 * self.m * float(v @ v) + 0.5 * float(w_b @ self.I_cm @ w_b)
        L_w = R @ (self.I_cm @ w_b) + self.m * np.cross(p, v)
        out = {
            "q": q,
            "w_body": w_b,
            "w_world": w_w,
            "E_kin": np.array(E_kin),
            "E_total": np.array(E_kin - self.m * float(self.g @ p)),
            "L_world": L_w,
            "L_body": R.T @ L_w,
        }
        if "sensor" in getattr(self.sc, "outputs", ()):
            # Exudyn's own body output at a local point (independent of the FMU's v = ω × r);
            # sensor_point is measured from the rotation point (pivot, else centre of mass)
            local = np.asarray(self.sc.sensor_point, dtype=float)
            if self.model == "joint":
                local = local - self.r_cm  # node at the centre of mass
            origin = np.asarray(mbs.GetObjectOutputBody(self.body, OVT.Position, localPosition=[0.0, 0.0, 0.0]))
            if self.model == "joint":
                origin = origin - R @ self.r_cm  # the pivot
            for key, ovt in (("sensor_r", OVT.Position), ("sensor_v", OVT.Velocity), ("sensor_a", OVT.Acceleration)):
                val = np.asarray(mbs.GetObjectOutputBody(self.body, ovt, localPosition=list(local)), dtype=float)
                out[key] = val - origin if key == "sensor_r" else val
        return out


def _settings(solver: str, tol: float, spectral_radius: float, newton_tol: float) -> exu.SimulationSettings:
    ss = exu.SimulationSettings()
    ss.solution.file.write = False  # no coordinates file
    ss.solution.sensors.active = False  # no sensor files
    ss.solution.restart.write = False
    ss.timeIntegration.verboseMode = 0
    ss.timeIntegration.verboseModeFile = 0
    ss.show.statistics = False
    ss.show.computationTime = False
    ss.show.globalTimers = False
    ss.timeIntegration.solverType = getattr(exu.DynamicSolverType, solver)
    ss.timeIntegration.startTime = 0.0
    if solver in EXPLICIT_SOLVERS:
        ss.timeIntegration.explicit.useLieGroupIntegration = True
        ss.timeIntegration.explicit.eliminateConstraints = True
        ss.timeIntegration.explicit.computeEndOfStepAccelerations = False
        ss.timeIntegration.automaticStepSize = solver == "DOPRI5"
        ss.timeIntegration.relativeTolerance = tol
        ss.timeIntegration.absoluteTolerance = tol
    else:
        ss.timeIntegration.automaticStepSize = False
        ss.timeIntegration.newton.relativeTolerance = newton_tol
        ss.timeIntegration.newton.absoluteTolerance = newton_tol
        ga = ss.timeIntegration.generalizedAlpha
        if solver == "GeneralizedAlpha":  # genuine generalized-α, index-3 constraints
            ga.useNewmark = False
            ga.useIndex2Constraints = False
            ga.spectralRadius = spectral_radius
        else:  # TrapezoidalIndex2 = Newmark β = 1/4, γ = 1/2 with index-2 constraints (as SolveDynamic sets it)
            ga.useNewmark = True
            ga.useIndex2Constraints = True
            ga.newmarkBeta = 0.25
            ga.newmarkGamma = 0.5
        ga.lieGroupAddTangentOperator = True
    return ss


def build_exudyn_model(
    scene: Any, model: str | None = None, solver: str = "RK67", node_type: str = "RotVecLG", friction: str = "connector"
) -> _Model:
    """The assembled Exudyn system of a scene (for direct use of Exudyn's solvers).

    Returns an object with ``.SC`` (SystemContainer), ``.mbs`` (MainSystem), ``.node``
    (rigid-body node index), ``.loads`` ({"tau_body"/"tau_world": LoadIndex}),
    ``.set_torque(name, value)`` and ``.outputs()`` (current outputs as in ``simulate_scene``).
    """
    return _Model(scene, default_model(scene, solver) if model is None else model, node_type, friction)


def exudyn_settings(
    solver: str = "RK67", tol: float = 1e-10, spectral_radius: float = 0.9, newton_tol: float = 1e-12
) -> exu.SimulationSettings:
    """Simulation settings used by ``simulate_scene`` (no files written, no console output)."""
    return _settings(solver, tol, spectral_radius, newton_tol)


# ----------------------------------------------------------------------------------
# public: simulation
# ----------------------------------------------------------------------------------
def simulate_scene(
    scene: Any,
    stop_time: float | None = None,
    step: float | None = None,
    solver: str = "RK67",
    h: float | None = None,
    record_every: int | None = None,
    input_fn: InputFunction | None = None,
    *,
    model: str | None = None,
    node_type: str | None = None,
    friction: str = "connector",
    tol: float = 1e-10,
    spectral_radius: float = 0.9,
    newton_tol: float = 1e-12,
    inputs: str = "continuous",
) -> dict[str, Any]:
    """Simulate a scene with an Exudyn multibody model, co-simulation style.

    scene: a ``modelsrc.scene.Scene`` (read as data only).
    stop_time (s), step (communication step, s): default the scene's. The communication
    points are 0, step, 2 step, ..., stop_time plus the switching times of the scene's
    input tables (when ``input_fn`` is None), as in the FMU driver.
    solver: "RK44", "RK67", "DOPRI5" (explicit, Lie-group ``NodeRigidBodyRotVecLG``) or
    "TrapezoidalIndex2", "GeneralizedAlpha" (implicit; index-2 trapezoidal rule resp.
    generalized-α with index-3 constraints and spectral radius ``spectral_radius``).
    h: internal step (s), default ``scene.fixed_step``; each communication interval Δ is split
    into ⌈Δ/h⌉ equal steps (use powers of two for step-for-step comparisons). For DOPRI5
    h is the maximum step; the step size is controlled to rtol = atol = ``tol``.
    record_every: record every k-th communication point (default 1; t = 0 and the last
    point are always recorded).
    input_fn(t, outputs) -> {"tau_body[k]"/"tau_world[k]": value (N·m)}: called at every
    communication point with the current outputs ("q[1]".."q[4]", "w_body[1]", ...,
    "E_kin", ...); the torques are held until the next point; components not returned
    keep their value (start 0). Without it the scene's inputs are used: constants and
    tables (constant over each interval, sampled at its start) and, with inputs
    "continuous", a harmonic torque as a load user function of time; with "hold" every
    input held over the interval at its mean there (``Scene.input_mean``).
    model: "free", "pivot" or "joint" (see module docstring); default ``default_model``.
    node_type: "RotVecLG" (default; the only one the explicit solvers take) or
    "EulerParameters" (implicit solvers only).
    friction: "connector" (rigid-body spring-damper to ground) or "user" (load user function).

    Returns numpy arrays over the recorded times: "time" (n,) s; "w_body" (n,3) rad/s body;
    "q" (n,4) scalar first, body -> world, sign-continuous; "w_world" (n,3) rad/s world;
    "E_kin", "E_total" (n,) J (E_total = E_kin − m g·(R r_cm), pivot reference);
    "L_world", "L_body" (n,3) N·m·s about the pivot for gravity scenes, about the centre of
    mass otherwise; plus "wall_time" (s, stepping loop incl. output evaluation), "cpu_time" (s,
    the process's CPU time over the same loop),
    "n_steps" (internal steps taken), "model", "solver", "node_type".
    """
    T = float(scene.stop_time if stop_time is None else stop_time)
    H = float(scene.step if step is None else step)
    h = float(scene.fixed_step if h is None else h)
    every = 1 if record_every is None else int(record_every)
    for label, v in (("stop_time", T), ("step", H), ("h", h)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"{label} must be a finite number > 0 (s), got {v}")
    if every < 1:
        raise ValueError(f"record_every must be >= 1, got {record_every}")
    if _has(scene, "translation") or _has(scene, "moving_pivot"):
        raise ValueError("the reference point of this scene moves: use rbcheck.exudyn.motion.simulate_motion")
    if solver not in EXPLICIT_SOLVERS + IMPLICIT_SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; use one of {EXPLICIT_SOLVERS + IMPLICIT_SOLVERS}")
    model = default_model(scene, solver) if model is None else model
    if model not in ("free", "pivot", "joint"):
        raise ValueError(f"model must be 'free', 'pivot' or 'joint', got {model!r}")
    if model == "free" and _has(scene, "gravity"):
        raise ValueError("model 'free' has no gravity; use 'pivot' or 'joint' for a gravity scene")
    if model != "free" and not _has(scene, "gravity"):
        raise ValueError(f"model {model!r} needs a gravity scene (pivot and r_cm)")
    if model == "joint" and solver in EXPLICIT_SOLVERS:
        raise ValueError(
            "Exudyn's explicit solvers cannot treat the spherical joint: use model 'pivot' "
            "or an implicit solver (TrapezoidalIndex2, GeneralizedAlpha)"
        )
    node_type = "RotVecLG" if node_type is None else node_type
    if node_type not in NODE_TYPES:
        raise ValueError(f"node_type must be one of {NODE_TYPES}, got {node_type!r}")
    if node_type == "EulerParameters" and solver in EXPLICIT_SOLVERS:
        raise ValueError("Euler-parameter nodes need an implicit solver; explicit solvers take RotVecLG")

    if inputs not in ("continuous", "hold"):
        raise ValueError(f"inputs must be 'continuous' or 'hold', got {inputs!r}")
    held = inputs == "hold"
    varying = list(getattr(scene, "inputs_varying_in_step", [])) if input_fn is None and not held else []
    mdl = _Model(scene, model, node_type, friction, varying)
    inputs = getattr(scene, "inputs", {}) or {}
    switch = (
        []
        if input_fn is not None
        else [float(t) for v in inputs.values() if np.ndim(v) == 2 for t in np.asarray(v)[:, 0]]
    )
    grid = comm_times(T, H, switch)
    ss = _settings(solver, tol, spectral_radius, newton_tol)
    dt0 = float(grid[1] - grid[0])
    n0 = max(1, math.ceil(dt0 / h * (1.0 - 1e-12)))
    ss.timeIntegration.endTime = float(grid[1])
    ss.timeIntegration.numberOfSteps = n0
    ss.timeIntegration.initialStepSize = dt0 / n0
    ss.timeIntegration.minimumStepSize = min(1e-12, 1e-6 * dt0 / n0)
    exu_solver = exu.MainSolverExplicit() if solver in EXPLICIT_SOLVERS else exu.MainSolverImplicitSecondOrder()

    u = {name: np.zeros(3) for name in mdl.loads}
    rec: dict[str, list] = {k: [] for k in ("time", "q", "w_body", "w_world", "E_kin", "E_total", "L_world", "L_body")}

    def flat(out: dict[str, np.ndarray]) -> dict[str, float]:
        d: dict[str, float] = {}
        for k, v in out.items():
            if v.ndim == 0:
                d[k] = float(v)
            else:
                d.update({f"{k}[{i + 1}]": float(x) for i, x in enumerate(v)})
        return d

    n_steps = 0
    t_wall, t_cpu = _time.perf_counter(), _time.process_time()
    if not exu_solver.InitializeSolver(mdl.mbs, ss):
        raise RuntimeError(
            f"Exudyn: {solver} could not be initialised for model {model!r}: {exu_solver.GetErrorString()}"
        )
    out = mdl.outputs()
    last = len(grid) - 1
    for i in range(last + 1):
        t = float(grid[i])
        if i % every == 0 or i == last:
            rec["time"].append(t)
            for k, v in out.items():
                rec.setdefault(k, []).append(v)
        if i == last:
            break
        if mdl.loads:
            if input_fn is not None:
                for key, val in dict(input_fn(t, flat(out))).items():
                    base, _, idx = key.partition("[")
                    if base not in u or not idx.endswith("]"):
                        raise KeyError(
                            f"input_fn returned {key!r}; this scene's inputs are "
                            f"{[f'{b}[{j}]' for b in u for j in (1, 2, 3)]}"
                        )
                    u[base][int(idx[:-1]) - 1] = float(val)
            else:
                for name in u:
                    if name in inputs and held and hasattr(scene, "input_mean"):
                        u[name] = scene.input_mean(name, t, float(grid[i + 1]))
                    elif name in inputs and name not in varying:
                        u[name] = _table_value(inputs[name], t)
            for name, val in u.items():
                if name not in varying:
                    mdl.set_torque(name, val)
        dt = float(grid[i + 1]) - t
        ns = max(1, math.ceil(dt / h * (1.0 - 1e-12)))
        exu_solver.it.startTime = t
        exu_solver.it.endTime = float(grid[i + 1])
        exu_solver.it.maxStepSize = dt / ns
        if not exu_solver.SolveSteps(mdl.mbs, ss):
            raise RuntimeError(f"Exudyn {solver} failed on [{t}, {grid[i + 1]}] s: {exu_solver.GetErrorString()}")
        n_steps += exu_solver.it.currentStepIndex - 1
        out = mdl.outputs()
    exu_solver.FinalizeSolver(mdl.mbs, ss)
    wall, cpu = _time.perf_counter() - t_wall, _time.process_time() - t_cpu

    res: dict[str, Any] = {k: np.asarray(v, dtype=float) for k, v in rec.items()}
    res.update(wall_time=wall, cpu_time=cpu, n_steps=int(n_steps), model=model, solver=solver, node_type=node_type)
    return res


# ----------------------------------------------------------------------------------
# public: inertia through Exudyn's RigidBodyInertia utilities
# ----------------------------------------------------------------------------------
def exudyn_inertia_cylinder(mass: float, radius: float, height: float, axis: int = 2) -> np.ndarray:
    """Solid cylinder about its centre (kg·m², body frame), symmetry axis = body ``axis``.

    Exudyn's ``InertiaCylinder`` takes a density: ρ = m / (π R² h) (kg/m³).
    """
    rho = mass / (math.pi * radius**2 * height)
    return np.array(rbu.InertiaCylinder(density=rho, length=height, outerRadius=radius, axis=axis).Inertia())


def exudyn_inertia_disc(mass: float, radius: float, axis: int = 2) -> np.ndarray:
    """Thin solid disc about its centre (kg·m²): ``InertiaCylinder`` with thickness 1e-9 R.

    Exudyn has no disc; the thickness adds (h/R)²/3 ≈ 3e-19 relative to the transverse
    moments, below double-precision round-off.
    """
    return exudyn_inertia_cylinder(mass, radius, 1e-9 * radius, axis)


def exudyn_inertia_cuboid(mass: float, a: float, b: float, c: float) -> np.ndarray:
    """Solid cuboid, edges a, b, c (m) along body x, y, z, about its centre (kg·m²).

    Exudyn's ``InertiaCuboid`` takes a density: ρ = m / (a b c).
    """
    return np.array(rbu.InertiaCuboid(density=mass / (a * b * c), sideLengths=[a, b, c]).Inertia())


def exudyn_inertia_sphere(mass: float, radius: float) -> np.ndarray:
    """Solid sphere about its centre (kg·m²), Exudyn's ``InertiaSphere``."""
    return np.array(rbu.InertiaSphere(mass=mass, radius=radius).Inertia())


def exudyn_inertia_point_masses(masses: Sequence[float], positions: Sequence[Sequence[float]]) -> np.ndarray:
    """Point masses (kg) at positions (m, body frame), inertia about the origin (kg·m²).

    Sum of Exudyn ``InertiaMassPoint(m).Translated(r)`` (reference point stays the origin).
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    total = None
    for m, r in zip(masses, pos):
        part = rbu.InertiaMassPoint(float(m)).Translated(r)
        total = part if total is None else total + part
    return np.array(total.Inertia())


def exudyn_inertia_translated(inertia_cm: np.ndarray, mass: float, r: Sequence[float]) -> np.ndarray:
    """Inertia about a point P (kg·m²) given the inertia about the centre of mass.

    r: P -> centre of mass (m, body frame); Exudyn ``RigidBodyInertia(m, I_cm).Translated(r)``.
    """
    rbi = rbu.RigidBodyInertia(mass=float(mass), inertiaTensor=np.asarray(inertia_cm, dtype=float))
    return np.array(rbi.Translated(np.asarray(r, dtype=float)).Inertia())


def exudyn_inertia_rotated(inertia: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Inertia in a rotated frame, R I Rᵀ (kg·m²), Exudyn ``RigidBodyInertia.Rotated(R)``.

    ``rotation`` maps old-frame coordinates to new-frame ones (v' = R v).
    """
    rbi = rbu.RigidBodyInertia(mass=1.0, inertiaTensor=np.asarray(inertia, dtype=float))
    return np.array(rbi.Rotated(np.asarray(rotation, dtype=float)).Inertia())


_SHAPES: dict[str, Callable[..., np.ndarray]] = {
    "cylinder": exudyn_inertia_cylinder,
    "disc": exudyn_inertia_disc,
    "cuboid": exudyn_inertia_cuboid,
    "sphere": exudyn_inertia_sphere,
    "point_masses": exudyn_inertia_point_masses,
    "translated": exudyn_inertia_translated,
    "rotated": exudyn_inertia_rotated,
}


def exudyn_inertia(kind: str, *args: Any, **kwargs: Any) -> np.ndarray:
    """Dispatch to the ``exudyn_inertia_<kind>`` helper (kg·m², 3×3, body frame).

    kind: "cylinder", "disc", "cuboid", "sphere", "point_masses", "translated", "rotated".
    """
    try:
        fn = _SHAPES[kind]
    except KeyError:
        raise ValueError(f"unknown kind {kind!r}; use one of {sorted(_SHAPES)}") from None
    return fn(*args, **kwargs)
