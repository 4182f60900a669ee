"""Exudyn reference of the gyrostat: each rotor a second rigid body on a revolute joint to the hub.

The independent check of the FMU's rotors (docs/theory.md §8): no gyrostat equations
here, only Exudyn's multibody formulation. The hub carries the scene's inertia minus each
rotor's (axial J, transverse J/2: a disc; only the sum matters for the gyrostat, the split
is arbitrary) and minus the rotors' parallel-axis terms where they sit off the centre of
mass; a generic joint (`GenericJoint`, all but the rotation about the rotor axis
constrained) ties each rotor to the hub at the rotor's position (docs/theory.md §8.7).

- Torque mode (§8.1): the motor is a body-fixed torque pair, +u g on the rotor, −u g on the
  hub (g is fixed in both). u is the physical input: held between the communication
  points (an importer's loop, sampled from this model's own outputs) or a table's rows
  (its switching times join the grid), or a harmonic evaluated at every solver time.
- Speed mode (§8.5): the rotor's rate relative to the hub is prescribed by a velocity-level
  coordinate constraint between the two nodes' local angular velocities about g,
  ω_rotor·g − ω_hub·g = Ω(t) (the motor torque is its Lagrange multiplier);
  a propeller's thrust k_f Ω² g and drag −k_m Ω|Ω| g (§8.6) are loads on the rotor.
- Command mode (§8.8): the same constraint, with Ω(t) the lag's solution for a constant
  command, Ω_cmd + (Ω(0) − Ω_cmd) e^(−t/τ_m) (`_lag`): Exudyn checks how the body answers
  the rotor's motion, the closed form of the lag itself is rbcheck.closed_forms.motor_lag.

Why these choices (measured, docs/theory.md §8.7):
- Rotation-vector Lie-group nodes (`NodeRigidBodyRotVecLG`): the trapezoidal rule on
  Euler parameters makes an error that grows like Ω (Ω h)² in a spinning rotor's rate
  (5e-3 rad/s at h = 1e-3 s on a wheel spun to 20 rad/s); the Lie-group update rotates
  about the spin axis exactly (1.1e-7).
- The accelerations corrected at every input jump (`_jump`): the trapezoidal rule
  v₊ = v + h/2 (a + a₊) carries the acceleration a of the previous step, computed with the
  old loads; uncorrected, each jump of u is an O(h) error and the run first order.
- Node frames turned by a constant 2 rad (`node_offset`, `rotor_offset`): Exudyn's
  composition of rotation vectors loses the angle near 0 (the slew ends at the identity).
- A consistent start of speed-mode rotors (`_consistent_start`): Exudyn's initial
  accelerations leave out a constraint's time derivative.
- The trapezoidal rule (index 2); Exudyn's generalized-α (index 3) diverges on these nodes
  at coarse steps.
Units SI; q scalar first, body -> world.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import exudyn as exu
import numpy as np
from exudyn import itemInterface as ii
from exudyn import rigidBodyUtilities as rbu

from ..numerics.rotation_np import matrix_to_quat
from .models import comm_times, inertia6

__all__ = ["RotorInputFunction", "covers", "implicit_settings", "simulate_gyrostat"]

OVT = exu.OutputVariableType
TRANSVERSE_FRACTION = 0.5  # a rotor's transverse inertia / its axial one (a thin disc)
# each body's mass (kg) without translation: the centres of mass coincide, so it acts on nothing rotational
MASS = 1.0
ROTOR_MASS_FRACTION = 0.01  # with translation: each rotor's share of the scene's mass (the hub has the rest)
NODE_OFFSET_ANGLE = 2.0  # rad: the nodes' frames are the bodies' turned by this (node_offset)
SUPPORTED_FEATURES = frozenset({"translation", "gravity"})  # gravity only with translation (no pivot)

# u(t, outputs) -> {"u_<name>": N·m}, held over the communication step, as the FMU driver does
RotorInputFunction = Callable[[float, Mapping[str, float]], Mapping[str, float]]


def _prescribed(rotor: Any) -> bool:
    """True when the rotor's rate relative to the hub is a known function of time: speed
    mode (its schedule) or command mode (the lag's solution, `_lag`)."""
    return rotor.mode in ("speed", "command")


def _lag(scene: Any, name: str) -> tuple[Callable[[float], float], Callable[[float], float]]:
    """t -> Ω(t), Ω̇(t) (rad/s, rad/s²) of a command-mode rotor under its constant command:
    Ω = Ω_cmd + (Ω(0) − Ω_cmd) e^(−t/τ_m), Ω̇ = (Ω_cmd − Ω)/τ_m (docs/theory.md §8.8)."""
    r = scene.rotors[name]
    tau, W0, c = float(r.settings["tau_m"]), float(r.Omega0), float(scene.input_at(f"Omega_cmd_{name}", 0.0)[0])
    return (lambda t: c + (W0 - c) * math.exp(-t / tau)), (lambda t: (W0 - c) * math.exp(-t / tau) / -tau)


def covers(scene: Any) -> str | None:
    """None when this model covers the scene, else the reason it does not: rotors on a
    free hub (with translation and gravity at most, no force points), the speed- and
    command-mode rotors' axes along one body axis (the constraint acts on one coordinate of
    each node's local angular velocity, and the node frames are turned about that axis:
    `node_offset`), a command-mode rotor's command constant (`_lag`)."""
    if not scene.rotors:
        return "the scene has no rotors"
    extra = sorted(set(scene.features) - SUPPORTED_FEATURES)
    if extra or scene.force_points:
        return f"the Exudyn gyrostat models a free hub with rotors (translation, gravity); the scene also has {extra}"
    if scene.has("gravity") and not scene.has("translation"):
        return "gravity about a pivot: the Exudyn gyrostat models a free hub"
    for name, r in scene.rotors.items():
        if r.mode not in ("torque", "speed", "command"):
            return f"rotor {name!r} is in mode {r.mode!r}, which this model does not know"
        if r.mode == "command" and np.ndim(scene.inputs.get(f"Omega_cmd_{name}", 0.0)) != 1:
            return f"command-mode rotor {name!r} has a command that changes (a table or a harmonic), not a constant"
    speed = [(name, np.asarray(r.axis, dtype=float)) for name, r in scene.rotors.items() if _prescribed(r)]
    for name, g in speed:
        if _axis_index(g) is None:
            return f"{scene.rotors[name].mode}-mode rotor {name!r} has axis {list(g)}, not along a body axis"
        if abs(abs(float(g @ speed[0][1])) - 1.0) > 1e-14:
            return f"speed- or command-mode rotors {speed[0][0]!r} and {name!r} have axes that are not parallel"
    return None


def _axis_index(g: np.ndarray) -> tuple[int, float] | None:
    """(k, s) when g = s e_k (s = ±1), else None."""
    k = int(np.argmax(np.abs(g)))
    if abs(abs(g[k]) - 1.0) > 1e-14 or np.count_nonzero(np.delete(g, k)):
        return None
    return k, float(np.sign(g[k]))


def _frame_with_z(g: np.ndarray) -> np.ndarray:
    """A rotation matrix whose third column is the unit vector g (the joint's free z axis)."""
    t = np.array([1.0, 0.0, 0.0]) if abs(g[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(t, g)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(g, x), g])


def _parallel(m: float, r: np.ndarray) -> np.ndarray:
    """m (|r|² 1 − r rᵀ): the inertia (kg·m²) a point mass m at r adds (parallel-axis theorem)."""
    return m * (float(r @ r) * np.eye(3) - np.outer(r, r))


def _lie_group_node(mbs: Any, x: np.ndarray, v: np.ndarray, R: np.ndarray, w_world: np.ndarray) -> int:
    """A rotation-vector Lie-group node at position x (m) with velocity v (m/s), attitude R and
    angular velocity w_world (rad/s, world); its velocity coordinates are the local angular velocity."""
    rv = rbu.RotationMatrix2RotationVector(R)
    return mbs.AddNode(
        ii.NodeRigidBodyRotVecLG(
            referenceCoordinates=[*map(float, x), *map(float, rv)],
            initialVelocities=[*map(float, v), *map(float, R.T @ w_world)],
        )
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
    # Exudyn's recommended kinematic relations (Holzinger, Arnold, Gerstmayr): with node frames
    # as `node_offset` sets them, 10x smaller errors than Bruls-Cardona's on the slew at h = 1e-3 s
    ga.lieGroupSimplifiedKinematicRelations = False
    return ss


@dataclass
class _Rotor:
    """One rotor's Exudyn items: its node, axis g (body frame), g_h and g_r (the same axis in
    the hub's and in the rotor's node frame), D (the rotor node's frame is the body's turned
    by D), inertia I_n (rotor node frame, kg·m²), position (m, body,
    from the centre of mass), motor loads (torque mode: on the rotor, on the hub), the speed
    constraint (speed mode)."""

    name: str
    g: np.ndarray
    g_h: np.ndarray
    g_r: np.ndarray
    D: np.ndarray
    I_n: np.ndarray
    position: np.ndarray
    speed: bool
    node: int = -1
    loads: tuple[int, int] = (-1, -1)
    constraint: int = -1
    sign: float = 1.0  # speed mode: g_h = g_r = sign e_k
    probe: tuple[int, int] = (-1, -1)  # speed mode: a torque pair used only to start consistently
    Omega_dot: Callable[[float], float] | None = None


def _schedule(scene: Any, key: str) -> Callable[[float], float]:
    """t -> the scene's scalar input `key` at t (s)."""
    return lambda t: float(scene.input_at(key, t)[0])


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation matrix of `angle` (rad) about the unit vector `axis` (Rodrigues)."""
    K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def node_offset(scene: Any) -> np.ndarray:
    """C: the hub node's frame is the body's turned by C (constant), 2 rad about the axis m
    the body mainly turns about, so that a run ending at (or starting from) the identity
    attitude does not bring the node's rotation vector to 0.

    Why: Exudyn composes rotation vectors with w = π − 2 atan2(x, √(1 − x²)), x = cos(w/2),
    which loses the angle's precision near w = 0 (relative error ε/(w²/4): 4 % at 1e-7 rad).
    On reaction_wheel_slew, which ends at the identity, the slew then stalled at 7e-7 rad
    while the FMU's (and the exact recursion's) angle reached 1.8e-7 rad, whatever h; with C
    the final attitude agrees to 1.3e-10 rad at h = 1e-3 s. Why about m: Exudyn's Lie-group
    trapezoidal rule is not invariant under a constant turn of a node's frame; it is most
    accurate when the rotation vector stays along the axis of the motion (dual_spin, nutation
    amplitude 1e-5 rad/s, h = 1e-3 s: 2.6e-8 rad/s off with C about the spin axis, 4.4e-6
    with C 2 rad about a transverse axis). m: the common axis of the speed-mode rotors (their
    constraint needs g on one node axis, which a turn about g keeps), else the start
    attitude's rotation axis, else the start rate's direction, else body z."""
    speed_axes = [np.asarray(r.axis, dtype=float) for r in scene.rotors.values() if _prescribed(r)]
    if speed_axes:
        m = speed_axes[0]
        if any(abs(abs(float(g @ m)) - 1.0) > 1e-14 for g in speed_axes):
            raise ValueError("the Exudyn gyrostat needs the speed-mode rotors' axes parallel (one node axis)")
        return _rotation(m, NODE_OFFSET_ANGLE)
    for v in (np.asarray(scene.q0[1:], dtype=float), np.asarray(scene.w0, dtype=float), np.array([0.0, 0.0, 1.0])):
        if np.linalg.norm(v) > 0.0:
            return _rotation(v / np.linalg.norm(v), NODE_OFFSET_ANGLE)
    raise AssertionError("unreachable")


def rotor_offset(C: np.ndarray, g: np.ndarray) -> np.ndarray:
    """D: a rotor node's frame is its body's turned by D, chosen so that the rotor spins about
    a coordinate axis of its node: C when C keeps g on one (a speed-mode rotor's constraint
    needs g on the same axis of both nodes), else a frame whose z axis is g.

    Why: Exudyn's Lie-group trapezoidal rule is not invariant under a constant turn of a
    node's frame (`node_offset`); a wheel spinning fast about an oblique local axis was far
    less accurate (dual_spin, wheel at 101 rad/s, h = 2e-4 / 1e-4 s Richardson against the
    FMU: |Δω| 1.0e-6 rad/s with every frame turned 2 rad about y, 1.0e-8 with the wheel's
    spin on its local z)."""
    if _axis_index(C.T @ g) is not None:
        return C
    return _frame_with_z(g)


def _jump(solver: Any, mbs: Any, ss: exu.SimulationSettings, t0: float, apply: Callable[[], None]) -> None:
    """Change the loads at t0 (`apply`) and give the integrator the accelerations that go
    with them: a₊ = a + (a_init(new loads) − a_init(old loads)) at the current state.

    The trapezoidal rule carries the acceleration a of the end of the last step, computed
    with the old loads; without the correction each jump of u costs an O(h) error and the
    run is first order. Exudyn's own initial accelerations (InitializeSolverInitialConditions
    from the current state) are not accurate enough with Lie-group nodes turning (its
    constraint term (C_q q̇)_q q̇ is differentiated in the rotation-vector coordinates, while
    the velocity coordinates are local angular velocities: a restart alone left the slew's
    wheels 3e-4 rad/s off at h = 1e-3 s with u constant), but that term does not depend on
    the loads, so it cancels in the difference."""
    data = mbs.systemData
    initial = exu.ConfigurationType.Initial
    a = np.asarray(data.GetODE2Coordinates_tt(), dtype=float)
    data.SetODE2Coordinates(data.GetODE2Coordinates(), configuration=initial)
    data.SetODE2Coordinates_t(data.GetODE2Coordinates_t(), configuration=initial)
    data.SetAECoordinates(data.GetAECoordinates(), configuration=initial)
    ss.timeIntegration.startTime = t0
    solver.InitializeSolverInitialConditions(mbs, ss)
    a_old = np.asarray(data.GetODE2Coordinates_tt(), dtype=float)
    apply()
    solver.InitializeSolverInitialConditions(mbs, ss)
    a_new = np.asarray(data.GetODE2Coordinates_tt(), dtype=float)
    data.SetODE2Coordinates_tt(list(a + (a_new - a_old)))


def _consistent_start(
    solver: Any, mbs: Any, ss: exu.SimulationSettings, hub_node: int, rotors: list[_Rotor]
) -> dict[str, float]:
    """Start the integrator with accelerations that satisfy the speed constraints at the
    acceleration level, Ω̇_rotor = Ω̇(0).

    Exudyn's initial accelerations leave out a constraint's explicit time derivative, so a
    prescribed Ω(t) with Ω̇(0) ≠ 0 starts with a wrong rotor acceleration; the trapezoidal
    rule keeps that error as an undamped (−1)ⁿ oscillation of the accelerations and the
    multipliers (the motor torque was J Ω̇(0) = 2.4e-3 N·m off on quadrotor at every
    communication point), though the positions and velocities are unaffected. Here the
    speed constraints are switched off and replaced by torque pairs F (on rotor and hub);
    the rotors' relative accelerations are affine in F, so Exudyn's initialisation at F = 0
    and at a unit F per rotor gives the F that makes them Ω̇(0); the accelerations at that F
    are the consistent ones. Returns F (N·m by rotor name): the motor torques at t = 0."""
    speed = [r for r in rotors if r.speed]
    if not speed:
        return {}
    data = mbs.systemData
    hub_idx = list(data.GetNodeLTGODE2(hub_node))[3:6]
    idx = [list(data.GetNodeLTGODE2(r.node))[3:6] for r in speed]

    def rel_acc(a: np.ndarray) -> np.ndarray:
        return np.array([float(r.g_r @ a[i] - r.g_h @ a[hub_idx]) for r, i in zip(speed, idx)])

    def init(F: np.ndarray) -> np.ndarray:
        for r, f in zip(speed, F):
            mbs.SetLoadParameter(r.probe[0], "loadVector", list(float(f) * r.g_r))
            mbs.SetLoadParameter(r.probe[1], "loadVector", list(-float(f) * r.g_h))
        solver.InitializeSolverInitialConditions(mbs, ss)
        return np.asarray(data.GetODE2Coordinates_tt(), dtype=float)

    for r in speed:
        mbs.SetObjectParameter(r.constraint, "activeConnector", False)
    zero = np.zeros(len(speed))
    a0 = init(zero)
    S = np.column_stack([rel_acc(init(np.eye(len(speed))[k])) - rel_acc(a0) for k in range(len(speed))])
    target = np.array([r.Omega_dot(0.0) for r in speed])  # type: ignore[misc]
    F = np.linalg.solve(S, target - rel_acc(a0))
    a = init(F)
    for r in speed:
        mbs.SetObjectParameter(r.constraint, "activeConnector", True)
    init(zero)  # the solver's state with the constraints back on
    data.SetODE2Coordinates_tt(list(a))
    return {r.name: float(f) for r, f in zip(speed, F)}


def simulate_gyrostat(
    scene: Any,
    stop_time: float | None = None,
    step: float | None = None,
    h: float = 1e-4,
    input_fn: RotorInputFunction | None = None,
    solver: str = "TrapezoidalIndex2",
    newton_tol: float = 1e-12,
) -> dict[str, Any]:
    """The scene's gyrostat in Exudyn (module docstring; a scene it does not cover raises
    ValueError with the reason, `covers`).

    stop_time, step (s): default the scene's; h: internal step (s), the largest that divides
    each communication interval; input_fn(t, outputs) -> {"u_<name>": N·m} held over each
    communication step (outputs as returned below, at t, vectors also by component as the
    FMU names them: 'q[1]', 'w_body[3]'): a digital controller sampling this model's own
    state; without it each torque-mode u follows the scene's schedule as the physical input
    (a harmonic continuously, a table switching at its rows' times, 0 without one), and each
    speed-mode Ω its schedule (a constant or a harmonic). Returns over the communication
    points: "time" (n,) s, "q" (n,4), "w_body" (n,3) rad/s hub frame, "Omega_<name>" (n,)
    rad/s rotor rate relative to the hub, "u_<name>" (n,) N·m the motor torque of a
    speed-mode rotor (from the constraint's multiplier), "L_world" (n,3) N·m·s total about
    the centre of mass, "E_kin" (n,) J, with translation "x_cm", "v_cm" (n,3) m, m/s world;
    "wall_time" s."""
    why = covers(scene)
    if why is not None:
        raise ValueError(f"scene {scene.name}: {why}")
    T = float(scene.stop_time if stop_time is None else stop_time)
    H = float(scene.step if step is None else step)
    translation = scene.has("translation")
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    q0 = np.asarray(scene.q0, dtype=float)
    R0 = rbu.EulerParameters2RotationMatrix(q0)
    C = node_offset(scene)
    w0 = R0 @ np.asarray(scene.w0, dtype=float)  # world
    x0 = np.asarray(scene.x0, dtype=float) if translation else np.zeros(3)
    v0 = np.asarray(scene.v0, dtype=float) if translation else np.zeros(3)
    M = float(scene.mass) if translation else MASS * (1 + len(scene.rotors))
    m_r = ROTOR_MASS_FRACTION * M if translation else MASS
    rotors: list[_Rotor] = []
    I_hub = np.asarray(scene.inertia, dtype=float).copy()
    for name, r in scene.rotors.items():
        g = np.asarray(r.axis, dtype=float)
        I_r = r.J * np.outer(g, g) + TRANSVERSE_FRACTION * r.J * (np.eye(3) - np.outer(g, g))
        pos = np.asarray(r.position, dtype=float) if r.position is not None else np.zeros(3)
        I_hub = I_hub - I_r - _parallel(m_r, pos)
        D = rotor_offset(C, g)
        rotors.append(_Rotor(name, g, C.T @ g, D.T @ g, D, D.T @ I_r @ D, pos, _prescribed(r)))
    m_hub = M - m_r * len(rotors)
    c = -sum((m_r * r.position for r in rotors), np.zeros(3)) / m_hub  # the hub's centre of mass (body)
    I_hub = I_hub - _parallel(m_hub, c)
    if np.linalg.eigvalsh(I_hub)[0] <= 0:
        raise ValueError("the hub's inertia (the scene's minus the rotor discs') is not positive definite")

    def start_rate(r: _Rotor) -> float:
        if scene.rotors[r.name].mode == "speed":
            return float(scene.input_at(f"Omega_{r.name}", 0.0)[0])
        return float(scene.rotors[r.name].Omega0)

    hub_node = _lie_group_node(mbs, x0 + R0 @ c, v0 + np.cross(w0, R0 @ c), R0 @ C, w0)
    I_hub_n = C.T @ I_hub @ C
    hub = mbs.AddObject(ii.ObjectRigidBody(mass=m_hub, inertia=inertia6(I_hub_n), nodeNumber=hub_node))
    bodies = [(hub_node, m_hub, I_hub_n)]
    held: dict[str, float] = {}  # torque-mode u held over the current interval (N·m)
    for rot in rotors:
        pos = rot.position
        w_rot = w0 + start_rate(rot) * (R0 @ rot.g)
        rot.node = _lie_group_node(mbs, x0 + R0 @ pos, v0 + np.cross(w0, R0 @ pos), R0 @ rot.D, w_rot)
        body = mbs.AddObject(ii.ObjectRigidBody(mass=m_r, inertia=inertia6(rot.I_n), nodeNumber=rot.node))
        bodies.append((rot.node, m_r, rot.I_n))
        A = _frame_with_z(rot.g)  # the joint frame (body coordinates), free about its z = g
        ht_hub = exu.HT(rotation=C.T @ A, translation=C.T @ (pos - c))
        jh = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=hub, localHT=ht_hub))
        ht_rot = exu.HT(rotation=rot.D.T @ A, translation=[0.0] * 3)
        jr = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=body, localHT=ht_rot))
        mbs.AddObject(ii.GenericJoint(markerNumbers=[jh, jr], constrainedAxes=[1, 1, 1, 1, 1, 0]))
        m_rot = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=body, localPosition=[0.0] * 3))
        sr = scene.rotors[rot.name]
        g_r, g_h = rot.g_r, rot.g_h
        if rot.speed:  # ω_rotor·g − ω_hub·g = Ω(t) on the nodes' local angular velocities, g_h = g_r = s e_k
            ax = _axis_index(g_h)
            assert ax is not None  # covers() and node_offset() checked it
            axis_k, sgn = ax
            rot.sign = sgn
            command = sr.mode == "command"
            Om, rot.Omega_dot = _lag(scene, rot.name) if command else (
                _schedule(scene, f"Omega_{rot.name}"), _schedule(scene, f"Omega_dot_{rot.name}"))  # fmt: skip
            mh = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=hub_node, coordinate=3 + axis_k))
            mr = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=rot.node, coordinate=3 + axis_k))
            constant = not command and f"Omega_{rot.name}" not in scene.inputs_varying_in_step  # no Python call
            if constant:
                rot.constraint = mbs.AddObject(
                    ii.ObjectConnectorCoordinate(markerNumbers=[mh, mr], velocityLevel=True, offset=sgn * Om(0.0))
                )
            else:
                rot.constraint = mbs.AddObject(
                    ii.ObjectConnectorCoordinate(
                        markerNumbers=[mh, mr],
                        velocityLevel=True,
                        offsetUserFunction_t=lambda mbs_, t, i, off, sgn=sgn, Om=Om: sgn * Om(t),
                    )
                )
            m_hub_marker = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=hub, localPosition=list(C.T @ (pos - c))))
            rot.probe = (
                mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_rot, bodyFixed=True, loadVector=[0.0] * 3)),
                mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_hub_marker, bodyFixed=True, loadVector=[0.0] * 3)),
            )
            if sr.propeller and constant:  # thrust k_f Ω² g and drag −k_m Ω|Ω| g on the rotor (§8.6)
                W = Om(0.0)
                mbs.AddLoad(
                    ii.LoadForceVector(markerNumber=m_rot, bodyFixed=True, loadVector=list(sr.k_f * W**2 * g_r))
                )
                drag = list(-sr.k_m * W * abs(W) * g_r)
                mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_rot, bodyFixed=True, loadVector=drag))
            elif sr.propeller:  # the same, body-fixed, Ω(t) evaluated at every solver time
                kf, km = sr.k_f, sr.k_m
                mbs.AddLoad(ii.LoadForceVector(markerNumber=m_rot, bodyFixed=True,
                                               loadVectorUserFunction=lambda mbs_, t, v, Om=Om, kf=kf, g=g_r:
                                               list(kf * Om(t) ** 2 * g)))  # fmt: skip
                mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_rot, bodyFixed=True,
                                                loadVectorUserFunction=lambda mbs_, t, v, Om=Om, km=km, g=g_r:
                                                list(-km * Om(t) * abs(Om(t)) * g)))  # fmt: skip
            continue
        m_hub_marker = mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=hub, localPosition=list(C.T @ (pos - c))))
        if input_fn is None and f"u_{rot.name}" in scene.inputs_varying_in_step:
            # a harmonic: the physical input, evaluated at every solver time
            u_t = _schedule(scene, f"u_{rot.name}")
            fr = lambda mbs_, t, v, u=u_t, g=g_r: list(u(t) * g)
            fh = lambda mbs_, t, v, u=u_t, g=g_h: list(-u(t) * g)
            lr = mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_rot, bodyFixed=True, loadVectorUserFunction=fr))
            lh = mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_hub_marker, bodyFixed=True, loadVectorUserFunction=fh))
        else:  # held: a constant, a table's row, or the importer's sample (new_inputs)
            held[rot.name] = 0.0
            lr = mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_rot, bodyFixed=True, loadVector=[0.0] * 3))
            lh = mbs.AddLoad(ii.LoadTorqueVector(markerNumber=m_hub_marker, bodyFixed=True, loadVector=[0.0] * 3))
        rot.loads = (lr, lh)
    if scene.has("gravity"):
        gravity = np.asarray(scene.g, dtype=float)
        for node, m, _ in bodies:
            mm = mbs.AddMarker(ii.MarkerNodePosition(nodeNumber=node))
            mbs.AddLoad(ii.LoadForceVector(markerNumber=mm, loadVector=list(m * gravity)))
    mbs.Assemble()
    by_name = {r.name: r for r in rotors}
    torque_rotors = [r for r in rotors if not r.speed]

    q_prev = q0.copy()

    def outputs() -> dict[str, Any]:
        nonlocal q_prev
        Rn = np.asarray(mbs.GetNodeOutput(hub_node, OVT.RotationMatrix), dtype=float).reshape(3, 3)
        w_n = np.asarray(mbs.GetNodeOutput(hub_node, OVT.AngularVelocityLocal), dtype=float)
        q = matrix_to_quat(Rn @ C.T)
        if float(q @ q_prev) < 0.0:
            q = -q
        q_prev = q
        xs, vs, Ls, E = [], [], np.zeros(3), 0.0
        for node, m, I in bodies:
            Rk = np.asarray(mbs.GetNodeOutput(node, OVT.RotationMatrix), dtype=float).reshape(3, 3)
            wk = np.asarray(mbs.GetNodeOutput(node, OVT.AngularVelocityLocal), dtype=float)
            xs.append(np.asarray(mbs.GetNodeOutput(node, OVT.Position), dtype=float))
            vs.append(np.asarray(mbs.GetNodeOutput(node, OVT.Velocity), dtype=float))
            Ls = Ls + Rk @ (I @ wk)
            E += 0.5 * float(wk @ I @ wk) + 0.5 * m * float(vs[-1] @ vs[-1])
        ms = np.array([m for _, m, _ in bodies])
        x_cm = ms @ np.array(xs) / ms.sum()
        v_cm = ms @ np.array(vs) / ms.sum()
        for m, x, v in zip(ms, xs, vs):
            Ls = Ls + m * np.cross(x - x_cm, v - v_cm)
        out: dict[str, Any] = {"q": q, "w_body": C @ w_n}
        for r in rotors:
            wr = np.asarray(mbs.GetNodeOutput(r.node, OVT.AngularVelocityLocal), dtype=float)
            out[f"Omega_{r.name}"] = np.array(float(r.g_r @ wr - r.g_h @ w_n))
            if r.speed:  # the multiplier λ of ω_r,k − ω_h,k − sΩ = 0: the torque −λ e_k on the rotor
                lam = float(np.ravel(mbs.GetObjectOutput(r.constraint, OVT.Force))[0])
                out[f"u_{r.name}"] = np.array(-lam * r.sign)
        out["L_world"] = Ls
        out["E_kin"] = np.array(E)
        if translation:
            out["x_cm"], out["v_cm"] = x_cm, v_cm
        return out

    ss = implicit_settings(solver, newton_tol)
    grid = comm_times(T, H, scene.switch_times() if input_fn is None else [])
    exu_solver = exu.MainSolverImplicitSecondOrder()

    def steps(t0: float, t1: float) -> int:
        return max(1, math.ceil((t1 - t0) / h * (1.0 - 1e-12)))

    def new_inputs(t: float, t1: float, out: dict[str, Any]) -> dict[str, float]:
        """The held motor torques (N·m by rotor name) for the interval [t, t1] (s): a table's
        row in force inside it (read at its middle: a row time within round-off of a grid
        point switches there), or the importer's sample at t."""
        if input_fn is None:
            vals = {f"u_{n}": float(scene.input_at(f"u_{n}", 0.5 * (t + t1))[0]) for n in held}
        else:
            flat = {k: float(v) for k, v in out.items() if np.ndim(v) == 0}  # named as the FMU's outputs
            flat.update({f"{k}[{j + 1}]": float(x) for k, v in out.items() if np.ndim(v) == 1 for j, x in enumerate(v)})
            vals = dict(input_fn(t, flat))
        new = {}
        for key, val in vals.items():
            r = by_name.get(key.removeprefix("u_"))
            if r is None or r.speed or not key.startswith("u_"):
                raise KeyError(f"input {key!r}: the motor-torque inputs are {[f'u_{r.name}' for r in torque_rotors]}")
            new[r.name] = float(val)
        return new

    def apply(values: Mapping[str, float]) -> None:
        for name, val in values.items():
            held[name] = val
            r = by_name[name]
            mbs.SetLoadParameter(r.loads[0], "loadVector", list(val * r.g_r))
            mbs.SetLoadParameter(r.loads[1], "loadVector", list(-val * r.g_h))

    # the inputs at t = 0 before the solver starts: the trapezoidal rule starts from the
    # accelerations InitializeSolver computes, with the loads as they are then
    apply(new_inputs(0.0, float(grid[1]), outputs()))
    ss.timeIntegration.endTime = float(grid[1])
    ss.timeIntegration.numberOfSteps = steps(0.0, float(grid[1]))
    t_wall = _time.perf_counter()
    if not exu_solver.InitializeSolver(mbs, ss):
        raise RuntimeError(f"Exudyn: {solver} could not be initialised: {exu_solver.GetErrorString()}")
    u_start = _consistent_start(exu_solver, mbs, ss, hub_node, rotors)
    out = outputs()
    out.update({f"u_{n}": np.array(u) for n, u in u_start.items()})  # the multipliers are not set yet
    rec: dict[str, list] = {"time": []}
    for i in range(len(grid)):
        t = float(grid[i])
        rec["time"].append(t)
        for k, v in out.items():
            rec.setdefault(k, []).append(v)
        if i == len(grid) - 1:
            break
        t1 = float(grid[i + 1])
        ns = steps(t, t1)
        if i > 0:
            new = new_inputs(t, t1, out)
            if any(held[n] != v for n, v in new.items()):
                _jump(exu_solver, mbs, ss, t, lambda new=new: apply(new))
        exu_solver.it.startTime = t
        exu_solver.it.endTime = t1
        exu_solver.it.maxStepSize = (t1 - t) / ns
        if not exu_solver.SolveSteps(mbs, ss):
            raise RuntimeError(f"Exudyn {solver} failed on [{t}, {t1}] s: {exu_solver.GetErrorString()}")
        out = outputs()
    exu_solver.FinalizeSolver(mbs, ss)
    res: dict[str, Any] = {k: np.asarray(v, dtype=float) for k, v in rec.items()}
    res["wall_time"] = _time.perf_counter() - t_wall
    return res
