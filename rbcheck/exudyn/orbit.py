"""Exudyn reference of a body in a circular orbit: a free rigid body, the gravity-gradient torque a load user function.

The rigid body of ``rbcheck.exudyn.models`` (model "free": a Lie-group rotation-vector node,
explicit RK solvers) gets a body-fixed ``LoadTorqueVector`` whose user function evaluates
τ = 3 n² ĉ × (I ĉ) from the node's current rotation matrix R and the time t:
ĉ = Rᵀ (−sin n t, 0, cos n t) (docs/theory.md §9.1, §9.2). The user function is called
at every stage of the explicit method with that stage's state (the friction load of
``exudyn_models`` relies on the same: it reads the stage's ω), so the reference keeps
the solver's order: RK67 against scipy's DOP853 at rtol 1e-13 over the shipped scene's three
orbits, 3.0e-6, 4.6e-8, 7.0e-10, 1.2e-11 in q at h = 200, 100, 50, 25 s (ratios 65, 65, 60:
sixth order). Units SI; q body → world (scalar first), ω body frame.
"""

from __future__ import annotations

import math
import time as _time
from typing import Any

import exudyn as exu
import numpy as np
from exudyn import itemInterface as ii

from .models import build_exudyn_model, comm_times, exudyn_settings

OVT = exu.OutputVariableType


def simulate_orbit(
    scene: Any, stop_time: float | None = None, step: float | None = None, h: float = 10.0, solver: str = "RK67"
) -> dict[str, Any]:
    """Exudyn run of an orbit scene with features.gravity_gradient (principal or full I about
    the centre of mass, no other torque): "time" (s), "q" (n, 4), "w_body" (n, 3) rad/s at the
    communication points, "wall_time" (s), "n_steps"; fixed steps h (s) of the explicit solver."""
    if not (scene.has("orbit") and scene.has("gravity_gradient")):
        raise ValueError("simulate_orbit needs a scene with features.orbit and features.gravity_gradient")
    other = scene.features - {"orbit", "gravity_gradient"}
    if other or getattr(scene, "rotors", None):
        raise ValueError(
            f"simulate_orbit models the orbit's torque only; the scene also has {sorted(other) or 'rotors'}"
        )
    T = float(scene.stop_time if stop_time is None else stop_time)
    H = float(scene.step if step is None else step)
    n = float(scene.orbit_rate)
    I = np.asarray(scene.inertia, dtype=float)
    mdl = build_exudyn_model(scene, model="free", solver=solver)
    mbs, node = mdl.mbs, mdl.node
    marker = mbs.AddMarker(ii.MarkerNodeRigid(nodeNumber=node))

    def gravity_gradient(mbs_: Any, t: float, load_vector: Any) -> list[float]:
        R = np.asarray(mbs_.GetNodeOutput(node, OVT.RotationMatrix), dtype=float).reshape(3, 3)
        c = R.T @ np.array([-math.sin(n * t), 0.0, math.cos(n * t)])
        return list(3.0 * n * n * np.cross(c, I @ c))

    mbs.AddLoad(ii.LoadTorqueVector(markerNumber=marker, bodyFixed=True, loadVectorUserFunction=gravity_gradient))
    mbs.Assemble()
    grid = comm_times(T, H, [])
    ss = exudyn_settings(solver)
    ns0 = max(1, math.ceil((grid[1] - grid[0]) / h * (1.0 - 1e-12)))
    ss.timeIntegration.endTime = float(grid[1])
    ss.timeIntegration.numberOfSteps = ns0
    ss.timeIntegration.initialStepSize = float(grid[1] - grid[0]) / ns0
    ex = exu.MainSolverExplicit()
    t_wall = _time.perf_counter()
    if not ex.InitializeSolver(mbs, ss):
        raise RuntimeError(f"Exudyn {solver} could not be initialised: {ex.GetErrorString()}")
    out = mdl.outputs()
    qs, ws, n_steps = [out["q"]], [out["w_body"]], 0
    for i in range(len(grid) - 1):
        dt = float(grid[i + 1] - grid[i])
        ns = max(1, math.ceil(dt / h * (1.0 - 1e-12)))
        ex.it.startTime, ex.it.endTime, ex.it.maxStepSize = float(grid[i]), float(grid[i + 1]), dt / ns
        if not ex.SolveSteps(mbs, ss):
            raise RuntimeError(f"Exudyn {solver} failed on [{grid[i]}, {grid[i + 1]}] s: {ex.GetErrorString()}")
        n_steps += ex.it.currentStepIndex - 1
        out = mdl.outputs()
        qs.append(out["q"])
        ws.append(out["w_body"])
    ex.FinalizeSolver(mbs, ss)
    return {
        "time": np.asarray(grid, dtype=float),
        "q": np.asarray(qs),
        "w_body": np.asarray(ws),
        "wall_time": _time.perf_counter() - t_wall,
        "n_steps": int(n_steps),
    }
