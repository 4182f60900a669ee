"""Forced-torque part of the report: a torque smooth in time, held or interpolated inside each communication step.

The FMU's body (`torque_driven`: I = diag(1, 2, 3) kg·m², from rest) is driven by a body-frame
torque that is a smooth function of time, tau_body(t) = (a sin² t, b cos t, c) N·m, sampled
by the importer at its communication points t_k = k Δ, in three ways (docs/fmi_layer.md,
Inputs inside a step):

- held: the value at t_k, held over [t_k, t_k + Δ] (zero-order hold, any FMI importer);
- FMI 2.0 input derivatives: the value and its first three time derivatives at t_k
  (`fmi2SetRealInputDerivatives`), a cubic Taylor polynomial over the step;
- FMI 3.0 intermediate update: the importer's callback sets the exact torque at every
  internal node time the FMU asks for.

The error of each is measured against scipy's DOP853 at rtol 1e-13 on rbcheck's own
right-hand side (`rbcheck.baselines.rigid_body.RigidBodyODE`, no code shared with modelsrc) with the
torque evaluated exactly. A held input is a first-order error in Δ whatever the method; a
cubic Taylor polynomial leaves an input error O(Δ⁴) over a step, a global error O(Δ⁴); the
intermediate update leaves only the integrator's own error (the FMU's defaults: rk8 with
error control at tolerance 1e-10 per second, docs/theory.md §5.5).

Runnable alone: ``python -m rbcheck.workprecision.forced_inputs`` prints the table.
"""

from __future__ import annotations

import math
import shutil
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np
from scipy.integrate import solve_ivp

from modelsrc.scene import Scene
from rbcheck.baselines.rigid_body import RigidBodyODE
from rbcheck.numerics.rotation_np import quat_to_matrix, rotation_angle_between

from .forced_scenes import SceneHoldResult, measure_forced_scenes, write_forced_scenes
from .measurable import has_scipy_reference

SCENE = "torque_driven"
MODES = ("held", "fmi2_derivatives", "fmi3_intermediate")
MODE_TITLES = {
    "held": "held (zero-order hold)",
    "fmi2_derivatives": "FMI 2.0 input derivatives (cubic)",
    "fmi3_intermediate": "FMI 3.0 intermediate update",
}
DEFAULT_STEPS = (0.1, 0.05, 0.02, 0.01, 0.005)
REF_RTOL = 1e-13  # the reference's own error is ~1e-13 relative: far below every error measured
W_NAMES = [f"w_body[{k}]" for k in range(1, 4)]
Q_NAMES = [f"q[{k}]" for k in range(1, 5)]
TAU_NAMES = [f"tau_body[{k}]" for k in range(1, 4)]


class Torque(Protocol):
    """A body-frame torque given as a function of time (N·m; t in s) with its derivatives."""

    def __call__(self, t: float) -> np.ndarray: ...

    def derivative(self, t: float, order: int) -> np.ndarray: ...


@dataclass(frozen=True)
class SmoothTorque:
    """tau_body(t) = (a sin² t, b cos t, c) (N·m, body frame; t in s) and its time derivatives."""

    a: float = 0.5
    b: float = 0.3
    c: float = 0.2

    def derivative(self, t: float, order: int) -> np.ndarray:
        """d^order tau_body / dt^order at t (N·m/s^order, body frame), order 0..3."""
        s2, c2, s, c = math.sin(2 * t), math.cos(2 * t), math.sin(t), math.cos(t)
        # sin² t = (1 − cos 2t)/2: derivatives sin 2t, 2 cos 2t, −4 sin 2t
        first = (math.sin(t) ** 2, s2, 2 * c2, -4 * s2)[order]
        second = (c, -s, -c, s)[order]
        return np.array([self.a * first, self.b * second, self.c if order == 0 else 0.0])

    def __call__(self, t: float) -> np.ndarray:
        return self.derivative(t, 0)


@dataclass
class ForcedInputsResult:
    """Errors of the forced-torque runs: per mode, per communication step Δ (s), the largest
    over the check times of |ω − ω_ref| / max|ω_ref| (body frame, relative) and of the
    rotation angle between the FMU's and the reference attitude (rad); the internal steps
    per doStep of the last run; wall times (s) of the fmpy loops, for ratios."""

    steps: tuple[float, ...]
    stop_time: float
    torque: SmoothTorque
    e_w: dict[str, list[float]] = field(default_factory=dict)
    e_R: dict[str, list[float]] = field(default_factory=dict)
    wall: dict[str, list[float]] = field(default_factory=dict)
    internal_steps: dict[str, list[float]] = field(default_factory=dict)
    scenes: list[SceneHoldResult] = field(default_factory=list)  # rbcheck.workprecision.forced_scenes


def reference(torque: Callable[[float], np.ndarray], times: np.ndarray) -> np.ndarray:
    """States (q, ω) at `times` (s) of the scene's body from rest under tau_body = torque(t)
    (N·m, body frame): scipy DOP853 at rtol 1e-13, the torque evaluated exactly."""
    from modelsrc.scene import load_scene  # the scene's data (inertia, inputs) only

    ode = RigidBodyODE(load_scene(SCENE))

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        ode.set_inputs(tau_body=[float(v) for v in torque(t)], tau_world=[0.0, 0.0, 0.0])
        ode.prepare()
        return ode.rhs(t, y)

    y0 = np.array([1.0, 0, 0, 0, 0, 0, 0])
    sol = solve_ivp(rhs, (0.0, float(times[-1])), y0, method="DOP853", rtol=REF_RTOL, atol=1e-15, t_eval=times)
    if not sol.success:
        raise RuntimeError(f"reference failed: {sol.message}")
    return sol.y.T


def _errors(Y: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    """(relative ω error, attitude angle in rad), the largest over the rows."""
    e_w = float(np.max(np.linalg.norm(Y[:, 4:7] - ref[:, 4:7], axis=1)) / np.max(np.linalg.norm(ref[:, 4:7], axis=1)))
    angle = rotation_angle_between(quat_to_matrix(Y[:, :4]), quat_to_matrix(ref[:, :4]))
    return e_w, float(np.max(angle))


def run_fmu(
    fmu_path: Path,
    mode: str,
    dt: float,
    stop_time: float,
    torque: Torque,
    start: dict[str, float] | None = None,
    every: float = 0.1,
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Drive the FMU (FMI 2.0 archive for "fmi2_derivatives", else FMI 3.0) over [0,
    stop_time] with communication step dt (s), the torque given as `mode` says; start: start
    values (parameters, by name). Returns (check times, states (q, ω) there — one row every
    `every` s —, wall time (s) of the stepping loop, mean internal steps per doStep)."""
    from fmpy import extract, read_model_description

    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    tau_vr, out_vr = [vr[n] for n in TAU_NAMES], [vr[n] for n in Q_NAMES + W_NAMES]
    n_steps = round(stop_time / dt)
    stride = round(every / dt)
    unzip = extract(str(fmu_path))
    slave = None
    try:
        if md.fmiVersion.startswith("2"):
            from fmpy.fmi2 import FMU2Slave

            slave = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier)
            slave.instantiate()
            slave.setupExperiment(startTime=0.0, stopTime=stop_time)
            enter, set_real = slave.enterInitializationMode, slave.setReal
        else:
            from fmpy.fmi3 import FMU3Slave

            slave = FMU3Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier)
            fmu3 = slave

            def update(env, t, set_requested, get_allowed, finished, can_return, early, early_time):
                fmu3.setFloat64(tau_vr, [float(v) for v in torque(t)])

            if mode == "fmi3_intermediate":
                slave.instantiate(intermediateUpdate=update, requiredIntermediateVariables=tau_vr)
            else:
                slave.instantiate()
            enter = slave.enterInitializationMode
            set_real = slave.setFloat64
        reals = {k: v for k, v in (start or {}).items() if k != "method"}
        set_real([vr[k] for k in reals], [float(v) for v in reals.values()])
        if start and "method" in start:  # the Enumeration: FMI 2.0 Integer, FMI 3.0 Int64 access
            set_int = slave.setInteger if md.fmiVersion.startswith("2") else slave.setInt64
            set_int([vr["method"]], [int(start["method"])])
        if md.fmiVersion.startswith("2"):
            enter()
        else:
            enter(startTime=0.0, stopTime=stop_time)
        slave.exitInitializationMode()
        get = slave.getReal if md.fmiVersion.startswith("2") else slave.getFloat64
        rows, steps = [get(out_vr)], 0.0
        tic = time.perf_counter()
        for k in range(n_steps):
            t = k * dt
            set_real(tau_vr, [float(v) for v in torque(t)])
            if mode == "fmi2_derivatives":
                for order in (1, 2, 3):
                    slave.setRealInputDerivatives(tau_vr, [order] * 3, [float(v) for v in torque.derivative(t, order)])
            slave.doStep(t, dt)
            steps += get([vr["internal_steps"]])[0]
            if (k + 1) % stride == 0:
                rows.append(get(out_vr))
        wall = time.perf_counter() - tic
        times = np.arange(len(rows)) * stride * dt
        return times, np.array(rows), wall, steps / n_steps
    finally:
        if slave is not None:
            slave.terminate()
            slave.freeInstance()
        shutil.rmtree(unzip, ignore_errors=True)


def measure_forced_inputs(
    fmu3: Path,
    fmu2: Path,
    steps: Sequence[float] = DEFAULT_STEPS,
    stop_time: float = 4.0,
    torque: SmoothTorque | None = None,
    progress: Callable[[str], None] | None = None,
) -> ForcedInputsResult:
    """Run every mode at every communication step (s) over [0, stop_time] with the FMUs'
    default settings; errors against the scipy reference at every multiple of the largest step."""
    torque = torque or SmoothTorque()
    every = max(steps)
    res = ForcedInputsResult(tuple(steps), stop_time, torque)
    ref = reference(torque, np.arange(round(stop_time / every) + 1) * every)
    for mode in MODES:
        for key in ("e_w", "e_R", "wall", "internal_steps"):
            getattr(res, key)[mode] = []
        for dt in steps:
            if progress:
                progress(f"forced inputs {mode} Δ={dt:g}")
            fmu = fmu2 if mode == "fmi2_derivatives" else fmu3
            _, Y, wall, n_int = run_fmu(fmu, mode, dt, stop_time, torque, None, every)
            e_w, e_R = _errors(Y, ref)
            res.e_w[mode].append(e_w)
            res.e_R[mode].append(e_R)
            res.wall[mode].append(wall)
            res.internal_steps[mode].append(n_int)
    return res


def observed_order(steps: Sequence[float], errors: Sequence[float], floor: float = 1e-11) -> float | None:
    """Median slope of log error against log Δ between neighbouring steps with both errors
    above `floor` (below it the integrator's own error, not the input's, decides)."""
    slopes = [
        math.log(e0 / e1) / math.log(h0 / h1)
        for h0, h1, e0, e1 in zip(steps[:-1], steps[1:], errors[:-1], errors[1:])
        if e0 > floor and e1 > floor
    ]
    return float(np.median(slopes)) if slopes else None


def write_forced_inputs(w: Callable[[str], None], res: ForcedInputsResult) -> None:
    """Append the section: set-up, the error table (hold against interpolation), orders, cost."""
    tq = res.torque
    w("## Inputs inside a communication step\n")
    w(
        f"`{SCENE}` (I = diag(1, 2, 3) kg·m², from rest) driven by tau_body(t) = ({tq.a:g} sin² t, {tq.b:g} cos t, "
        f"{tq.c:g}) N·m for T = {res.stop_time:g} s with the FMU's default settings (rk8, error control at "
        "tolerance 1e-10 per second). The importer (fmpy) samples the torque at its communication points t_k = k Δ "
        "and either holds it over the step, or passes its first three derivatives there (FMI 2.0 "
        "`fmi2SetRealInputDerivatives`: a cubic over the step), or sets the exact torque at every internal node "
        "the FMU asks for (FMI 3.0 intermediate update). Error: the largest over t = 0, "
        f"{max(res.steps):g}, …, T of |ω − ω_ref| / max|ω_ref| and of the attitude angle (rad) against scipy DOP853 "
        f"at rtol {REF_RTOL:g} with the exact torque (`rbcheck.baselines.rigid_body.RigidBodyODE`).\n"
    )
    head = " | ".join(f"{MODE_TITLES[m]} e_ω | e_R (rad)" for m in MODES)
    w(f"| Δ (s) | {head} |")
    w("|---:|" + "---:|---:|" * len(MODES))
    for i, dt in enumerate(res.steps):
        cells = " | ".join(f"{res.e_w[m][i]:.1e} | {res.e_R[m][i]:.1e}" for m in MODES)
        w(f"| {dt:g} | {cells} |")
    w("")
    orders = []
    for m in MODES:
        p = observed_order(res.steps, res.e_w[m])
        orders.append(f"{MODE_TITLES[m]} {p:.2f}" if p is not None else f"{MODE_TITLES[m]} n/a (at the floor)")
    w(
        "Observed order in Δ of e_ω (median slope between neighbouring Δ with errors above 1e-11): "
        + ", ".join(orders)
        + ". Expected: 1 when held (the torque's first-order hold error), 4 for the cubic Taylor "
        "polynomial (its remainder is O(Δ⁴) per step), and no dependence on Δ for the intermediate update "
        "(the integrator's own error, set by the tolerance).\n"
    )
    i = len(res.steps) - 1
    base = res.wall["held"][i]
    w(
        f"Cost at Δ = {res.steps[i]:g} (wall time of the fmpy loop in this run, relative to held; internal steps "
        "per doStep): "
        + ", ".join(
            f"{MODE_TITLES[m]} {res.wall[m][i] / base:.2f}× ({res.internal_steps[m][i]:.2f} steps)" for m in MODES
        )
        + ". The intermediate update calls the importer's Python callback at every node of every internal step "
        "(11 per rk8 step: every node but the step's start), which dominates its time here; from C it costs a "
        "function call. Wall times were measured on a shared machine: compare them only within this run.\n"
    )
    write_forced_scenes(w, res.scenes)


def forced_scenes(scenes: Iterable[Scene]) -> list[Scene]:
    """The scenes of the continuous-against-held table: those with inputs that have a scipy
    reference and turn from their start (measurable.has_scipy_reference: not quadrotor nor
    reaction_wheel_slew, which start at rest)."""
    return [sc for sc in scenes if sc.inputs and has_scipy_reference(sc)]


def measure_inputs(
    timings: dict[str, float] | None = None,
    progress: Callable[[str], None] | None = None,
    build_dir: Path | None = None,
) -> ForcedInputsResult:
    """The report's part "inputs": build the scene's FMI 3.0 and 2.0 FMUs and those of the
    other scenes with inputs (host binary) and measure (also forced_scenes: continuous
    against held inputs per scene); its wall time (s) goes to timings["inputs"]. The FMUs
    go to a temporary folder, or to `build_dir`, where those built from the same sources
    are reused (fmu.build.build_fmu.ensure_fmu)."""
    from fmu.build.build_fmu import ensure_fmu
    from modelsrc.scene import list_scenes, load_scene

    tic = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="rbfmu_forced_") as tmp:
        where = tmp if build_dir is None else build_dir
        fmu3 = ensure_fmu(load_scene(SCENE), where)
        fmu2 = ensure_fmu(load_scene(SCENE), where, fmi_version=2)
        res = measure_forced_inputs(fmu3, fmu2, progress=progress)
        forced = forced_scenes(map(load_scene, list_scenes()))
        fmus = {sc.name: fmu3 if sc.name == SCENE else ensure_fmu(sc, where) for sc in forced}
        res.scenes = measure_forced_scenes(fmus, forced, progress=progress)
    if timings is not None:
        timings["inputs"] = time.perf_counter() - tic
    return res


def main(argv: Sequence[str] | None = None) -> int:
    """Measure (measure_inputs) and print the section's markdown on stdout."""
    del argv
    res = measure_inputs(progress=lambda s: print(s, file=sys.stderr))
    lines: list[str] = []
    write_forced_inputs(lines.append, res)
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
