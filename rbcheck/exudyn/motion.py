"""Exudyn models of a moving reference point: a free six-degree-of-freedom body and a top on a moving pivot.

An independent reference for the scenes with ``translation`` or ``moving_pivot``
(docs/theory.md §7): the equations of motion are Exudyn's, nothing of ``modelsrc`` or
``fmu`` is used, a scene is read as data (its fields and its input schedule,
``Scene.input_mean``). Conventions as in :mod:`rbcheck.exudyn.models`: SI units, world
= Exudyn's global frame, q scalar first body -> world, w_body in body axes.

* Free body (``translation``): an ``ObjectRigidBody`` on a ``NodeRigidBodyRotVecLG`` at
  the centre of mass, all six degrees of freedom free; uniform gravity a
  ``LoadMassProportional``; f_world, f_body and each force point a ``LoadForceVector`` on
  a ``MarkerBodyRigid`` at the point (``bodyFixed`` for body-frame forces: Exudyn then
  turns the force with the body and forms its moment itself); torque inputs
  ``LoadTorqueVector``; friction a body-fixed torque load −c ω (load user function).
  Explicit solvers (RK67 by default), accelerations evaluated at the end of each step.
* Moving pivot (``moving_pivot``): the top's node at its centre of mass, a
  ``SphericalJoint`` between a marker at the pivot point of the top (−r_cm, body) and a
  marker on a "shaker" mass point whose three coordinates follow the prescribed pivot
  motion through ``CoordinateConstraint`` s to ground with offset user functions: the
  position and velocity of the held pivot acceleration, x_k + v_k τ + ½ a_k τ²
  (τ = t − t_k) on each communication step, or (continuous inputs, a harmonic a_pivot)
  the closed-form double integral of the harmonic itself, a function of time
  (`MotionModel.follow_harmonic`). The weight is a ``LoadMassProportional``;
  Exudyn's explicit solvers cannot treat the joint, so the implicit
  ``TrapezoidalIndex2`` (default) or ``GeneralizedAlpha`` integrate it. Their
  accelerations and joint forces are not the physical ones where the held pivot
  acceleration jumps (measured with Exudyn 1.13.6 against finite differences of the
  velocities: 4.6 m/s² off with the index-2 trapezoidal rule, 0.16 m/s² with
  generalized-α at h = 2.5e-5 s), so this model outputs no a_cm, f_pivot or sensor
  acceleration; the checks take the centre-of-mass acceleration from its velocity
  (rbcheck.checks.motion).

The driver is co-simulation style, as ``exudyn_models.simulate_scene``: one solver
initialised once, ``SolveSteps`` per communication interval, the inputs held over it.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable, Mapping
from typing import Any

import exudyn as exu
import numpy as np
from exudyn import itemInterface as ii
from exudyn import rigidBodyUtilities as rbu

from ..numerics.rotation_np import matrix_to_quat
from .coverage import EXUDYN_FEATURES, covers
from .models import EXPLICIT_SOLVERS, IMPLICIT_SOLVERS, comm_times, exudyn_settings, inertia6, rotation_vector
from .models import simulate_scene as simulate_rotation

__all__ = ["EXUDYN_FEATURES", "MotionModel", "covers", "moves", "simulate", "simulate_motion"]

OVT = exu.OutputVariableType
InputFunction = Callable[[float, Mapping[str, float]], Mapping[str, float]]
MOTION_FEATURES = ("translation", "moving_pivot")


def _has(scene: Any, feature: str) -> bool:
    return feature in getattr(scene, "features", ())


def moves(scene: Any) -> bool:
    """True when the scene's reference point moves (translation or moving_pivot)."""
    return any(_has(scene, f) for f in MOTION_FEATURES)


def _input_names(scene: Any) -> list[str]:
    names = [n for f, n in (("torque_body", "tau_body"), ("torque_world", "tau_world")) if _has(scene, f)]
    names += [n for f, n in (("force_body", "f_body"), ("force_world", "f_world")) if _has(scene, f)]
    names += [f"f_{p}" for p in getattr(scene, "force_points", {})]
    return names + (["a_pivot"] if _has(scene, "moving_pivot") else [])


class MotionModel:
    """The assembled Exudyn system of a free body or a top on a moving pivot.

    ``set_inputs(u, t0)`` holds the inputs u (name -> 3-vector) from t0 on;
    ``outputs()`` gives the current outputs (names as the FMU's, vectors as arrays)."""

    def __init__(self, scene: Any):
        self.sc = scene
        self.pivot = _has(scene, "moving_pivot")
        mbs = self.mbs = (SC := exu.SystemContainer()).AddSystem()
        self.SC = SC
        self.I_cm = np.asarray(scene.inertia, dtype=float)
        self.m = float(scene.mass)
        self.g = np.asarray(scene.g, dtype=float) if _has(scene, "gravity") else np.zeros(3)
        self.r_cm = np.asarray(scene.r_cm, dtype=float) if self.pivot else np.zeros(3)
        q0, w0 = np.asarray(scene.q0, dtype=float), np.asarray(scene.w0, dtype=float)
        x0, v0 = np.asarray(scene.x0, dtype=float), np.asarray(scene.v0, dtype=float)
        R0 = rbu.EulerParameters2RotationMatrix(q0)
        # node at the centre of mass (a moving pivot's: x_B + R r_cm, v_B + R (ω × r_cm))
        pos0 = x0 + R0 @ self.r_cm
        vel0 = v0 + R0 @ np.cross(w0, self.r_cm)
        self.node = mbs.AddNode(
            ii.NodeRigidBodyRotVecLG(
                referenceCoordinates=list(pos0) + list(rotation_vector(q0)), initialVelocities=list(vel0) + list(w0)
            )
        )
        self.body = mbs.AddObject(ii.ObjectRigidBody(mass=self.m, inertia=inertia6(self.I_cm), nodeNumber=self.node))
        if _has(scene, "gravity"):
            mbs.AddLoad(
                ii.LoadMassProportional(
                    markerNumber=mbs.AddMarker(ii.MarkerBodyMass(bodyNumber=self.body)), loadVector=list(self.g)
                )
            )
        self.loads: dict[str, list[Any]] = {}
        points = {"f_body": (np.zeros(3), True), "f_world": (np.zeros(3), False)}
        points.update(
            {f"f_{n}": (np.asarray(fp.point, float), fp.frame == "body") for n, fp in scene.force_points.items()}
        )
        for name in _input_names(scene):
            if name.startswith("tau_"):
                mk = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=self.body, localPosition=[0.0, 0.0, 0.0]))
                load = ii.LoadTorqueVector(markerNumber=mk, bodyFixed=name == "tau_body", loadVector=[0.0, 0.0, 0.0])
                self.loads[name] = [mbs.AddLoad(load)]
            elif name.startswith("f_"):
                r, fixed = points[name]
                mk = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=self.body, localPosition=list(r)))
                self.loads[name] = [
                    mbs.AddLoad(ii.LoadForceVector(markerNumber=mk, bodyFixed=fixed, loadVector=[0.0] * 3))
                ]
        if _has(scene, "friction"):
            c = float(scene.c_friction)

            def friction(mbs_, t, load_vector, _n=self.node, _c=c):
                w = mbs_.GetNodeOutput(_n, OVT.AngularVelocityLocal)
                return [-_c * w[0], -_c * w[1], -_c * w[2]]

            mk = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=self.body, localPosition=[0.0, 0.0, 0.0]))
            mbs.AddLoad(ii.LoadTorqueVector(markerNumber=mk, bodyFixed=True, loadVectorUserFunction=friction))
        if self.pivot:
            self._add_shaker(x0, v0)
        mbs.Assemble()
        self.q_prev = q0.copy()

    def _add_shaker(self, x0: np.ndarray, v0: np.ndarray) -> None:
        """The pivot: a mass point whose coordinates follow the held pivot motion, joined
        to the top by a spherical joint (see the module docstring)."""
        mbs = self.mbs
        # segment of the held motion: (t_k, x_k, v_k, a_k), updated by set_inputs; per
        # coordinate the polynomial coefficients as Python floats (the user functions run
        # several times per Newton iteration: numpy scalars would double Exudyn's cost)
        self.seg = [0.0, x0.copy(), v0.copy(), np.zeros(3)]
        self.x_ref = x0.copy()
        self._coef = [(0.0, 0.0, float(v0[k]), 0.0) for k in range(3)]
        shaker = mbs.AddNode(ii.NodePoint(referenceCoordinates=list(x0), initialVelocities=list(v0)))
        mpoint = mbs.AddObject(ii.ObjectMassPoint(mass=1.0, nodeNumber=shaker))
        ground = mbs.AddNode(ii.NodePointGround())
        coef = self._coef
        harm: list[tuple[float, float, float, float, float] | None] = [None, None, None]
        self._harm = harm
        for k in range(3):

            def offset(mbs_, t, item, l_off, _k=k):  # coordinate = displacement from the reference x0
                if harm[_k] is not None:  # x − x0 = v0 t + off t²/2 − A/ω² (cos(ωt + φ) − cos φ) − A/ω sin φ t
                    v0, off, a, w, ph = harm[_k]
                    return t * (v0 + 0.5 * off * t - a / w * math.sin(ph)) - a / (w * w) * (
                        math.cos(w * t + ph) - math.cos(ph)
                    )
                t0, c0, c1, c2 = coef[_k]
                tau = t - t0
                return c0 + tau * (c1 + tau * c2)

            def offset_t(mbs_, t, item, l_off, _k=k):
                if harm[_k] is not None:  # v = v0 + off t + A/ω (sin(ωt + φ) − sin φ)
                    v0, off, a, w, ph = harm[_k]
                    return v0 + off * t + a / w * (math.sin(w * t + ph) - math.sin(ph))
                t0, _, c1, c2 = coef[_k]
                return c1 + 2.0 * c2 * (t - t0)

            m0 = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=ground, coordinate=k))
            m1 = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=shaker, coordinate=k))
            mbs.AddObject(
                ii.CoordinateConstraint(
                    markerNumbers=[m0, m1], offsetUserFunction=offset, offsetUserFunction_t=offset_t
                )
            )
        ms = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=mpoint, localPosition=[0.0, 0.0, 0.0]))
        mt = mbs.AddMarker(ii.MarkerBodyPosition(bodyNumber=self.body, localPosition=list(-self.r_cm)))
        mbs.AddObject(ii.SphericalJoint(markerNumbers=[ms, mt]))

    def follow_harmonic(self, spec: Any) -> None:
        """Move the pivot as the closed-form double integral of the harmonic pivot
        acceleration `spec` (modelsrc.scene_inputs.Harmonic, m/s², world) from the scene's
        x0, v0 at t = 0 (continuous input); `set_inputs` must then not set a_pivot."""
        v0 = self.sc.v0
        self._harm[:] = [
            (float(v0[k]), float(spec.offset[k]), float(spec.amplitude[k]), float(spec.omega), float(spec.phase))
            for k in range(3)
        ]

    def set_inputs(self, u: Mapping[str, np.ndarray], t0: float) -> None:
        """Hold the inputs (N·m, N, m/s²; frames as their names say) from t0 (s) on."""
        for name, val in u.items():
            if name == "a_pivot":
                _, x, v, a = self.seg
                tau = t0 - self.seg[0]
                self.seg = [t0, x + v * tau + 0.5 * a * tau * tau, v + a * tau, np.asarray(val, dtype=float)]
                _, x, v, a = self.seg
                self._coef[:] = [(t0, float(x[k] - self.x_ref[k]), float(v[k]), 0.5 * float(a[k])) for k in range(3)]
            else:
                for load in self.loads[name]:
                    self.mbs.SetLoadParameter(load, "loadVector", [float(x) for x in val])

    def outputs(self) -> dict[str, np.ndarray]:
        """Current outputs (SI; frames as the FMU's names say) from Exudyn's outputs."""
        mbs, n = self.mbs, self.node
        R = np.asarray(mbs.GetNodeOutput(n, OVT.RotationMatrix), dtype=float).reshape(3, 3)
        w_b = np.asarray(mbs.GetNodeOutput(n, OVT.AngularVelocityLocal), dtype=float)
        x_c = np.asarray(mbs.GetNodeOutput(n, OVT.Position), dtype=float)
        v_c = np.asarray(mbs.GetNodeOutput(n, OVT.Velocity), dtype=float)
        a_c = np.asarray(mbs.GetNodeOutput(n, OVT.Acceleration), dtype=float)
        q = matrix_to_quat(R)
        if float(q @ self.q_prev) < 0.0:  # sign continuity
            q = -q
        self.q_prev = q
        E_kin = 0.5 * self.m * float(v_c @ v_c) + 0.5 * float(w_b @ self.I_cm @ w_b)
        L_w = R @ (self.I_cm @ w_b)  # about the centre of mass
        out = {"q": q, "w_body": w_b, "w_world": R @ w_b, "x_cm": x_c, "v_cm": v_c, "a_cm": a_c, "p": self.m * v_c}
        out.update(E_kin=np.array(E_kin), E_total=np.array(E_kin - self.m * float(self.g @ x_c)))
        if self.pivot:
            r_w = R @ self.r_cm
            x_b = x_c - r_w
            v_b = v_c - np.cross(R @ w_b, r_w)
            L_w = L_w + self.m * np.cross(r_w, v_c - v_b)  # about the moving pivot
            out.update(x_pivot=x_b, v_pivot=v_b)
            del out["a_cm"]  # not the physical acceleration (module docstring)
        out.update(L_world=L_w, L_body=R.T @ L_w)
        if "sensor" in getattr(self.sc, "outputs", ()):
            local = np.asarray(self.sc.sensor_point, dtype=float) - self.r_cm  # from the node at the centre of mass
            kinds = (("sensor_r", OVT.Position), ("sensor_v", OVT.Velocity), ("sensor_a", OVT.Acceleration))
            for key, ovt in kinds[:2] if self.pivot else kinds:
                out[key] = np.asarray(mbs.GetObjectOutputBody(self.body, ovt, localPosition=list(local)), dtype=float)
        return out


def simulate_motion(
    scene: Any,
    stop_time: float | None = None,
    step: float | None = None,
    solver: str | None = None,
    h: float | None = None,
    input_fn: InputFunction | None = None,
    tol: float = 1e-10,
    newton_tol: float = 1e-12,
    spectral_radius: float = 0.9,
    inputs: str = "continuous",
) -> dict[str, Any]:
    """Simulate a free body or a top on a moving pivot with Exudyn, co-simulation style.

    stop_time, step (communication step), h (internal step): s, default the scene's
    (h_max). solver: default "RK67" for a free body, "TrapezoidalIndex2" for a moving
    pivot (explicit solvers cannot treat its joint). The communication points are those
    of ``exudyn_models.simulate_scene`` (plus the input tables' switching times); the
    inputs are constant over each interval (tables switch on its ends) and a harmonic
    a_pivot follows its closed form in time (inputs "continuous"), or every input is held
    at the scene's ``input_mean`` over the interval ("hold"), or set by input_fn(t,
    outputs) -> {"f_body[1]": ..., "a_pivot[3]": ...} (held over the interval).

    Returns arrays over the communication points: "time" (n,); "q" (n, 4), "w_body",
    "w_world" (rad/s), "x_cm", "v_cm", "a_cm", "p" (world), "E_kin", "E_total" (J),
    "L_world", "L_body" (N·m·s, about the centre of mass, or the moving pivot), with a
    moving pivot "x_pivot", "v_pivot" (and no "a_cm"), with a sensor "sensor_r",
    "sensor_v" and (free body) "sensor_a"; and "wall_time" (s), "cpu_time" (s, the process's, same
    section), "n_steps", "solver"."""
    if getattr(scene, "rotors", None):
        raise ValueError("the scene has rotors: use rbcheck.exudyn.rotors.simulate_gyrostat (the rigid body has none)")
    if not moves(scene):
        raise ValueError("simulate_motion needs a scene with translation or moving_pivot; use simulate_scene")
    T = float(scene.stop_time if stop_time is None else stop_time)
    H = float(scene.step if step is None else step)
    h = float(scene.fixed_step if h is None else h)
    pivot = _has(scene, "moving_pivot")
    solver = ("TrapezoidalIndex2" if pivot else "RK67") if solver is None else solver
    for label, v in (("stop_time", T), ("step", H), ("h", h)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"{label} must be a finite number > 0 (s), got {v}")
    if solver not in EXPLICIT_SOLVERS + IMPLICIT_SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; use one of {EXPLICIT_SOLVERS + IMPLICIT_SOLVERS}")
    if pivot and solver in EXPLICIT_SOLVERS:
        raise ValueError(
            "the moving pivot is a joint: use TrapezoidalIndex2 or GeneralizedAlpha, not an explicit solver"
        )
    if inputs not in ("continuous", "hold"):
        raise ValueError(f"inputs must be 'continuous' or 'hold', got {inputs!r}")
    varying = scene.inputs_varying_in_step if inputs == "continuous" and input_fn is None else []
    if set(varying) - {"a_pivot"}:
        raise ValueError(
            f"continuous {', '.join(sorted(set(varying) - {'a_pivot'}))}: only a harmonic a_pivot is modelled "
            "continuously here; use inputs='hold'"
        )
    mdl = MotionModel(scene)
    if varying:
        mdl.follow_harmonic(scene.inputs["a_pivot"])
    grid = comm_times(T, H, [] if input_fn is not None else scene.switch_times())
    ss = exudyn_settings(solver, tol, spectral_radius, newton_tol)
    ss.timeIntegration.explicit.computeEndOfStepAccelerations = True  # a_cm, sensor_a at the points
    n0 = max(1, math.ceil(float(grid[1] - grid[0]) / h * (1.0 - 1e-12)))
    ss.timeIntegration.endTime = float(grid[1])
    ss.timeIntegration.numberOfSteps = n0
    ss.timeIntegration.initialStepSize = float(grid[1] - grid[0]) / n0
    ex = exu.MainSolverExplicit() if solver in EXPLICIT_SOLVERS else exu.MainSolverImplicitSecondOrder()
    names = _input_names(scene)
    u = {name: np.zeros(3) for name in names}
    rec: dict[str, list[np.ndarray]] = {"time": []}
    n_steps = 0
    tic, cpu0 = _time.perf_counter(), _time.process_time()
    if not ex.InitializeSolver(mdl.mbs, ss):
        raise RuntimeError(f"Exudyn: {solver} could not be initialised: {ex.GetErrorString()}")
    out = mdl.outputs()
    for i in range(len(grid)):
        t = float(grid[i])
        rec["time"].append(np.array(t))
        for k, v in out.items():
            rec.setdefault(k, []).append(v)
        if i == len(grid) - 1:
            break
        t1 = float(grid[i + 1])
        if input_fn is not None:
            flat = {f"{k}[{j + 1}]": float(x) for k, v in out.items() if v.ndim for j, x in enumerate(v)}
            for key, val in dict(input_fn(t, flat)).items():
                base, _, idx = key.partition("[")
                if base not in u or not idx.endswith("]"):
                    raise KeyError(f"input_fn returned {key!r}; this scene's inputs are {names}")
                u[base][int(idx[:-1]) - 1] = float(val)
        elif inputs == "hold":
            u = {name: scene.input_mean(name, t, t1) for name in names}
        else:
            u = {name: scene.input_at(name, t) for name in names if name not in varying}
        mdl.set_inputs(u, t)
        ns = max(1, math.ceil((t1 - t) / h * (1.0 - 1e-12)))
        ex.it.startTime, ex.it.endTime, ex.it.maxStepSize = t, t1, (t1 - t) / ns
        if not ex.SolveSteps(mdl.mbs, ss):
            raise RuntimeError(f"Exudyn {solver} failed on [{t}, {t1}] s: {ex.GetErrorString()}")
        n_steps += ex.it.currentStepIndex - 1
        out = mdl.outputs()
    ex.FinalizeSolver(mdl.mbs, ss)
    res: dict[str, Any] = {k: np.asarray(v, dtype=float) for k, v in rec.items()}
    res.update(wall_time=_time.perf_counter() - tic, cpu_time=_time.process_time() - cpu0, n_steps=int(n_steps),
               solver=solver)  # fmt: skip
    return res


def simulate(scene: Any, **kwargs: Any) -> dict[str, Any]:
    """Exudyn run of any scene the models cover (`covers`; ValueError with its reason
    otherwise): `simulate_motion` when its reference point moves, else
    ``exudyn_models.simulate_scene`` (keywords as there)."""
    why = covers(scene)
    if why is not None:
        raise ValueError(why)
    if moves(scene):
        allowed = {"stop_time", "step", "solver", "h", "input_fn", "tol", "newton_tol", "spectral_radius", "inputs"}
        return simulate_motion(scene, **{k: v for k, v in kwargs.items() if k in allowed})
    return simulate_rotation(scene, **kwargs)
