"""Exudyn reference of the gyrostat: each rotor a second rigid body on a revolute joint to the hub, with its motor.

The independent check of the FMU's rotors (docs/theory.md §8): no gyrostat equations
here, only Exudyn's multibody formulation. The hub carries the scene's inertia minus each
rotor's (axial J, transverse J/2: a disc; only the sum matters for the gyrostat, the split
is arbitrary), every body has its centre of mass at the origin, and a generic joint
(`GenericJoint`, all but the rotation about the rotor axis constrained) ties each rotor to
the hub. The motor torque u is a body-fixed torque pair: +u g on the rotor, −u g on the hub.
Euler-parameter nodes with Exudyn's implicit solvers (its explicit ones do not take
the joints; /work/shared/FACTS.md). Units SI; q scalar first, body -> world.
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

from .exudyn_models import comm_times, inertia6
from .rotation_np import matrix_to_quat

OVT = exu.OutputVariableType
TRANSVERSE_FRACTION = 0.5  # a rotor's transverse inertia / its axial one (a thin disc)
MASS = 1.0  # kg of each body: the centres of mass coincide, so it acts on nothing rotational

# u(t, outputs) -> {"u_<name>": N·m}, held over the communication step, as the FMU driver does
RotorInputFunction = Callable[[float, Mapping[str, float]], Mapping[str, float]]


def _frame_with_z(g: np.ndarray) -> np.ndarray:
    """A rotation matrix whose third column is the unit vector g (the joint's free z axis)."""
    t = np.array([1.0, 0.0, 0.0]) if abs(g[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(t, g)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(g, x), g])


def _rigid_node(mbs: Any, q0: np.ndarray, w_world: np.ndarray) -> int:
    """An Euler-parameter node at the origin with attitude q0 and angular velocity w_world (rad/s, world)."""
    ep_t = rbu.AngularVelocity2EulerParameters_t(w_world, q0)  # Exudyn wants world ω here
    return mbs.AddNode(
        ii.NodeRigidBodyEP(referenceCoordinates=[0.0, 0.0, 0.0, *q0], initialVelocities=[0.0] * 3 + list(ep_t))
    )


def implicit_settings(solver: str, newton_tol: float) -> exu.SimulationSettings:
    """Exudyn's settings for fixed steps of an implicit solver, no files written:
    "TrapezoidalIndex2" (Newmark β = 1/4, γ = 1/2, index-2 constraints) or "GeneralizedAlpha"
    (index 3, spectral radius 0.9); Newton to newton_tol (absolute and relative)."""
    if solver not in ("TrapezoidalIndex2", "GeneralizedAlpha"):
        raise ValueError(f"solver must be 'TrapezoidalIndex2' or 'GeneralizedAlpha', got {solver!r}")
    ss = exu.SimulationSettings()
    ss.solution.file.write = False
    ss.solution.sensors.active = False
    ss.solution.restart.write = False
    ss.timeIntegration.verboseMode = 0
    ss.timeIntegration.verboseModeFile = 0
    ss.timeIntegration.solverType = getattr(exu.DynamicSolverType, solver)
    ss.timeIntegration.automaticStepSize = False
    ss.timeIntegration.newton.relativeTolerance = newton_tol
    ss.timeIntegration.newton.absoluteTolerance = newton_tol
    ga = ss.timeIntegration.generalizedAlpha
    trapezoidal = solver == "TrapezoidalIndex2"
    ga.useNewmark = ga.useIndex2Constraints = trapezoidal
    if trapezoidal:
        ga.newmarkBeta, ga.newmarkGamma = 0.25, 0.5
    else:
        ga.spectralRadius = 0.9
    ga.lieGroupAddTangentOperator = True
    return ss


def simulate_gyrostat(
    scene: Any,
    stop_time: float | None = None,
    step: float | None = None,
    h: float = 1e-4,
    input_fn: RotorInputFunction | None = None,
    solver: str = "TrapezoidalIndex2",
    newton_tol: float = 1e-12,
) -> dict[str, Any]:
    """The scene's gyrostat in Exudyn (free hub about its centre of mass; torque inputs and
    other features are not modelled: a scene with them raises ValueError).

    stop_time, step (s): default the scene's; h: internal step (s); input_fn(t, outputs) ->
    {"u_<name>": N·m} held over each communication step (outputs as returned below, at t,
    vectors also by component as the FMU names them: 'q[1]', 'w_body[3]');
    without it each u follows the scene's schedule (``Scene.input_mean``: held over each step
    at its mean there; exact for constants and tables, whose switching times join the
    communication points; a harmonic is then off by O(H²)), 0 without one. Returns over the
    communication points: "time" (n,) s, "q" (n,4),
    "w_body" (n,3) rad/s hub frame, "Omega_<name>" (n,) rad/s rotor rate relative to the hub,
    "L_world" (n,3) N·m·s total about the centre of mass, "E_kin" (n,) J, "wall_time" s."""
    if any(getattr(r, "speed", False) for r in scene.rotors.values()):
        raise ValueError("the Exudyn gyrostat drives its rotors by motor torques; speed-mode rotors are not modelled")
    extra = set(scene.features)
    if extra or scene.force_points:
        raise ValueError(f"the Exudyn gyrostat models a free hub with rotors only; this scene also has {sorted(extra)}")
    T = float(scene.stop_time if stop_time is None else stop_time)
    H = float(scene.step if step is None else step)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    q0 = np.asarray(scene.q0, dtype=float)
    R0 = rbu.EulerParameters2RotationMatrix(q0)
    w0 = np.asarray(scene.w0, dtype=float)
    I_hub = np.asarray(scene.inertia, dtype=float).copy()
    rotors = []
    for name, r in scene.rotors.items():
        g = np.asarray(r.axis, dtype=float)
        I_r = r.J * np.outer(g, g) + TRANSVERSE_FRACTION * r.J * (np.eye(3) - np.outer(g, g))
        I_hub = I_hub - I_r
        rotors.append((name, g, I_r, r.Omega0))
    if np.linalg.eigvalsh(I_hub)[0] <= 0:
        raise ValueError("the hub's inertia (the scene's minus the rotor discs') is not positive definite")
    hub_node = _rigid_node(mbs, q0, R0 @ w0)
    hub = mbs.AddObject(ii.ObjectRigidBody(mass=MASS, inertia=inertia6(I_hub), nodeNumber=hub_node))
    loads: dict[str, tuple[int, int, np.ndarray]] = {}
    rotor_nodes: dict[str, tuple[int, np.ndarray, np.ndarray]] = {}
    for name, g, I_r, Om0 in rotors:
        node = _rigid_node(mbs, q0, R0 @ (w0 + Om0 * g))  # aligned with the hub at t = 0
        body = mbs.AddObject(ii.ObjectRigidBody(mass=MASS, inertia=inertia6(I_r), nodeNumber=node))
        A = _frame_with_z(g)
        m_hub = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=hub, localPosition=[0.0] * 3))
        m_rot = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=body, localPosition=[0.0] * 3))
        jh = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=hub, localHT=exu.HT(rotation=A, translation=[0.0] * 3)))
        jr = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=body, localHT=exu.HT(rotation=A, translation=[0.0] * 3)))
        mbs.AddObject(ii.GenericJoint(markerNumbers=[jh, jr], constrainedAxes=[1, 1, 1, 1, 1, 0]))
        # the motor: +u g on the rotor, −u g on the hub, both body-fixed (g is fixed in both)
        lr = mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_rot, bodyFixed=True, loadVector=[0.0] * 3))
        lh = mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_hub, bodyFixed=True, loadVector=[0.0] * 3))
        loads[name] = (lr, lh, g)
        rotor_nodes[name] = (node, g, I_r)
    mbs.Assemble()

    q_prev = q0.copy()

    def outputs() -> dict[str, Any]:
        nonlocal q_prev
        R = np.asarray(mbs.GetNodeOutput(hub_node, OVT.RotationMatrix), dtype=float).reshape(3, 3)
        w_b = np.asarray(mbs.GetNodeOutput(hub_node, OVT.AngularVelocityLocal), dtype=float)
        q = matrix_to_quat(R)
        if float(q @ q_prev) < 0.0:
            q = -q
        q_prev = q
        L = R @ (I_hub @ w_b)
        E = 0.5 * float(w_b @ I_hub @ w_b)
        out: dict[str, Any] = {"q": q, "w_body": w_b}
        for name, (node, g, I_r) in rotor_nodes.items():
            Rr = np.asarray(mbs.GetNodeOutput(node, OVT.RotationMatrix), dtype=float).reshape(3, 3)
            wr = np.asarray(mbs.GetNodeOutput(node, OVT.AngularVelocityLocal), dtype=float)
            L = L + Rr @ (I_r @ wr)
            E += 0.5 * float(wr @ I_r @ wr)
            out[f"Omega_{name}"] = np.array(float(g @ wr) - float(g @ w_b))  # g is fixed in both frames
        out["L_world"] = L
        out["E_kin"] = np.array(E)
        return out

    ss = implicit_settings(solver, newton_tol)
    grid = comm_times(T, H, scene.switch_times() if input_fn is None else [])
    exu_solver = exu.MainSolverImplicitSecondOrder()
    dt0 = float(grid[1] - grid[0])
    n0 = max(1, math.ceil(dt0 / h * (1.0 - 1e-12)))
    ss.timeIntegration.endTime = float(grid[1])
    ss.timeIntegration.numberOfSteps = n0
    ss.timeIntegration.initialStepSize = dt0 / n0

    def set_inputs(t: float, t1: float, out: dict[str, Any]) -> None:
        if input_fn is None:
            vals = {f"u_{n}": float(scene.input_mean(f"u_{n}", t, t1)[0]) for n in loads}
        else:
            flat = {k: float(v) for k, v in out.items() if np.ndim(v) == 0}  # named as the FMU's outputs
            flat.update({f"{k}[{j + 1}]": float(x) for k, v in out.items() if np.ndim(v) == 1 for j, x in enumerate(v)})
            vals = dict(input_fn(t, flat))
        for key, val in vals.items():
            name = key.removeprefix("u_")
            if name not in loads:
                raise KeyError(f"input_fn returned {key!r}; the inputs are {[f'u_{n}' for n in loads]}")
            lr, lh, g = loads[name]
            mbs.SetLoadParameter(lr, "loadVector", list(float(val) * g))
            mbs.SetLoadParameter(lh, "loadVector", list(-float(val) * g))

    # the inputs at t = 0 before the solver starts: the trapezoidal rule starts from the
    # accelerations InitializeSolver computes, with the loads as they are then
    set_inputs(0.0, float(grid[1]), outputs())
    t_wall = _time.perf_counter()
    if not exu_solver.InitializeSolver(mbs, ss):
        raise RuntimeError(f"Exudyn: {solver} could not be initialised: {exu_solver.GetErrorString()}")
    out = outputs()
    rec: dict[str, list] = {"time": []}
    for i in range(len(grid)):
        t = float(grid[i])
        rec["time"].append(t)
        for k, v in out.items():
            rec.setdefault(k, []).append(v)
        if i == len(grid) - 1:
            break
        if i > 0:
            set_inputs(t, float(grid[i + 1]), out)
        dt = float(grid[i + 1]) - t
        ns = max(1, math.ceil(dt / h * (1.0 - 1e-12)))
        exu_solver.it.startTime = t
        exu_solver.it.endTime = float(grid[i + 1])
        exu_solver.it.maxStepSize = dt / ns
        if not exu_solver.SolveSteps(mbs, ss):
            raise RuntimeError(f"Exudyn {solver} failed on [{t}, {grid[i + 1]}] s: {exu_solver.GetErrorString()}")
        out = outputs()
    exu_solver.FinalizeSolver(mbs, ss)
    res: dict[str, Any] = {k: np.asarray(v, dtype=float) for k, v in rec.items()}
    res["wall_time"] = _time.perf_counter() - t_wall
    return res
