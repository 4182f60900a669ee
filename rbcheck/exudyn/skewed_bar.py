"""The skewed bar of MIT 2.003J in Exudyn: the bar on a revolute joint, whose reaction torque is the bearing torque.

The independent reference of rbcheck.closed_forms.skewed_bar's formula (the same bar and
shaft, φ and θ̇ as there): Exudyn's own joint and integrators, nothing of modelsrc or fmu.
"""

from __future__ import annotations

import time

import exudyn as exu
import exudyn.itemInterface as ii
import numpy as np
from numpy.typing import NDArray

OVT = exu.OutputVariableType


def exudyn_revolute(
    I_a: float,
    I_t: float,
    mass: float,
    phi: float,
    theta_dot: float,
    stop_time: float,
    h: float = 2.0**-12,
    solver: str = "GeneralizedAlpha",
) -> dict[str, NDArray[np.float64]]:
    """The bar on a revolute joint about world x in Exudyn; returns time, the joint's
    reaction torque on the bar (N·m, world), ω (rad/s, world), and wall_time (s).

    The bar starts rotated by φ about world z and spinning at θ̇ about x; no drive is
    needed (the bearing torque has no component along the shaft), so the joint alone
    holds the motion and its reaction torque is what the bearings supply.
    Generalized-α (index 3, ρ∞ = 0.9) damps the start-up transient of the multipliers
    within ~0.05 s; trapezoidal index-2 keeps them oscillating step to step.
    """
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    c, s = np.cos(phi), np.sin(phi)
    R0 = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])  # body x along the bar
    w_body = R0.T @ np.array([theta_dot, 0.0, 0.0])
    # rotation vector of R0 (a rotation by φ about z)
    node = mbs.AddNode(
        ii.NodeRigidBodyRotVecLG(referenceCoordinates=[0, 0, 0, 0, 0, phi], initialVelocities=[0, 0, 0] + list(w_body))
    )
    J = np.diag([I_a, I_t, I_t])
    body = mbs.AddObject(ii.ObjectRigidBody(mass=mass, inertia=[J[0, 0], J[1, 1], J[2, 2], 0, 0, 0], nodeNumber=node))
    ground = mbs.AddObject(ii.ObjectGround())
    m0 = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    # joint frame J1 fixed in the bar, aligned with the world axes at t = 0 (rotation R0ᵀ in
    # body coordinates), so the free joint x axis is the shaft = world x
    m1 = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=body, localHT=exu.HT(rotation=R0.T, translation=[0, 0, 0])))
    joint = mbs.AddObject(ii.GenericJoint(markerNumbers=[m0, m1], constrainedAxes=[1, 1, 1, 0, 1, 1]))
    sensor = mbs.AddSensor(ii.SensorObject(objectNumber=joint, storeInternal=True, outputVariableType=OVT.TorqueLocal))
    sw = mbs.AddSensor(ii.SensorNode(nodeNumber=node, storeInternal=True, outputVariableType=OVT.AngularVelocity))
    sR = mbs.AddSensor(ii.SensorNode(nodeNumber=node, storeInternal=True, outputVariableType=OVT.RotationMatrix))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.solution.file.write = False
    ss.timeIntegration.numberOfSteps = round(stop_time / h)
    ss.timeIntegration.endTime = stop_time
    ss.timeIntegration.verboseMode = 0
    ss.solution.sensors.writePeriod = h  # every step
    ss.timeIntegration.newton.relativeTolerance = 1e-12
    ss.timeIntegration.newton.absoluteTolerance = 1e-12
    if solver == "TrapezoidalIndex2":
        dyn = exu.DynamicSolverType.TrapezoidalIndex2
    else:
        dyn = exu.DynamicSolverType.GeneralizedAlpha
        ss.timeIntegration.generalizedAlpha.spectralRadius = 0.9
    t0 = time.perf_counter()
    exu.SolveDynamic(mbs, ss, solverType=dyn)
    wall = time.perf_counter() - t0
    lam = mbs.GetSensorStoredData(sensor)
    w = mbs.GetSensorStoredData(sw)
    Rb = mbs.GetSensorStoredData(sR)[:, 1:10].reshape(-1, 3, 3)
    # For a revolute joint with free joint-x, Exudyn's TorqueLocal holds the multipliers
    # λ4, λ5 of the constraints t_x0·t_y1 = 0 and t_x0·t_z1 = 0 (ObjectJointGeneric docs);
    # the torque they exert is λ4 (t_x0 × t_y1) + λ5 (t_x0 × t_z1), with t_y1, t_z1 the
    # body-fixed joint axes: world axes of J1 = R_body R0ᵀ.
    tau = np.empty((len(lam), 3))
    for k in range(len(lam)):
        J1 = Rb[k] @ R0.T
        tx0 = np.array([1.0, 0.0, 0.0])
        tau[k] = lam[k, 2] * np.cross(tx0, J1[:, 1]) + lam[k, 3] * np.cross(tx0, J1[:, 2])
    return {"time": lam[:, 0], "tau_world": tau, "w_world": w[:, 1:4], "wall_time": wall}
