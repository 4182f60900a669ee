"""Co-simulation mode of the report: a closed loop with a Python controller, the FMU via fmpy against Exudyn.

The torque-driven body is stepped at Δ = cfg.cosim_dt (1 ms) through fmpy and through
Exudyn chunk by chunk, the same controller on both sides. The wall time of each loop is
split into controller, tool compute and fmpy overhead; the FMU's compute is timed by
fmu.bench.benchmark.fmu_compute_ctypes (fmi3DoStep in a raw ctypes loop), its C estimate from
the harness's ns per internal step (fmu.bench.benchmark.c_step_ns_all).
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fmu.bench.benchmark import fmu_compute_ctypes
from modelsrc.scene import Scene, load_scene

from ..baselines.rigid_body import AttitudePD, OneSampleDelay, Trajectory, closed_loop_scipy, run_exudyn
from ..numerics.rotation_np import quat_from_axis_angle
from .config import Config
from .harness import FmuDriver, advance, guarded, show
from .references import CHECK_ATOL, CHECK_RTOL, REF_ATOL, REF_RTOL, Reference, errors

if TYPE_CHECKING:
    from tqdm import tqdm


def cosim_controller() -> AttitudePD:
    """The co-simulation's controller: slew from rest to a 2 rad rotation about (1, 2, 2)/3
    with kp = 1 N·m, kd = 2 N·m·s/rad (I = diag(1, 2, 3) kg·m²: ωn ≈ 0.6–1 rad/s, damping
    0.6–1), against a constant world-frame disturbance of 0.02 N·m about y."""
    qt = quat_from_axis_angle(np.array([1.0, 2.0, 2.0]) / 3.0, 2.0)
    return AttitudePD(qt, kp=1.0, kd=2.0, tau_world=(0.0, 0.02, 0.0))


@dataclass
class CosimRun:
    """One co-simulation configuration: wall time split (s) and error at the end."""

    tool: str
    config: str
    total: float
    controller: float
    compute: float  # FMU: fmi3DoStep in a ctypes loop; Exudyn: total − controller
    overhead: float  # FMU: fmpy (total − controller − compute); Exudyn: 0 (not separable)
    err: float
    e_w: float
    e_R: float
    compute_c_estimate: float = float("nan")  # FMU: C ns per substep × substeps
    cpu: float = float("nan")  # Exudyn: the process's CPU time over the timed solve (s)


def fmu_cosim_once(drv: FmuDriver, method: str, h_max: float, dt: float, T: float) -> tuple[float, float, np.ndarray]:
    """(total s, controller s, final outputs) of one fmpy loop at Δ = dt (s) over [0, T]
    with the PD controller: per step getFloat64 of the 7 states, the controller,
    setFloat64 of the 6 torques (N·m), doStep."""
    ctrl = cosim_controller()
    drv.start(method, h_max, T)
    get, setf, do = drv.inst.get_float64, drv.inst.set_float64, drv.inst.step
    vrs = drv.out_vrs[:7]
    names = drv.out_names[:7]
    in_names = [f"{b}[{k}]" for b in ("tau_body", "tau_world") for k in (1, 2, 3)]
    in_vrs = drv.inst.value_references(in_names)
    n = round(T / dt)
    tic = time.perf_counter()
    out = get(vrs)
    for k in range(n):
        t = k * dt
        u = ctrl(t, dict(zip(names, out)))
        setf(in_vrs, [u[nm] for nm in in_names])
        do(t, dt)
        out = get(vrs)
    total = time.perf_counter() - tic
    return total, ctrl.time_spent, np.asarray(out)


def fmu_compute(drv: FmuDriver, method: str, h_max: float, dt: float, T: float) -> float:
    """Seconds spent in fmi3DoStep alone for the same number of Δ steps as the loop
    (fmu.bench.benchmark.fmu_compute_ctypes; the inputs stay at their start values, which does
    not change the substep count)."""
    drv.start(method, h_max, T)
    return fmu_compute_ctypes(drv.inst, dt, round(T / dt), f"{method}, h_max {h_max}")


def _exudyn_cosim(
    scene: Scene, T: float, dt: float, solver: str, h: float, tol: float, delayed: bool = False
) -> tuple[Trajectory, float]:
    """(trajectory, controller s) of one Exudyn loop, SolveSteps per Δ = dt (s), step h (s);
    delayed: the torques of the sample before (OneSampleDelay, the Jacobi masters' loop)."""
    ctrl = cosim_controller()
    tr = run_exudyn(scene, dt, T, solver, h=h, tol=tol, input_fn=OneSampleDelay(ctrl) if delayed else ctrl)
    return tr, ctrl.time_spent


@dataclass
class CosimResult:
    """Co-simulation section: T and dt (s), reference, runs, and the target evaluation
    (smallest speed-up and its (FMU, Exudyn) pair); c_ns: method -> ns per internal step
    through fmi3DoStep."""

    T: float
    dt: float
    ref: Reference
    runs: list[CosimRun]
    min_speedup: float | None
    min_pair: tuple[str, str] | None
    c_ns: dict[str, float]
    ecos: object | None = None  # the same loop in ECOS (cosim_ecos.EcosCosim), when measured


# (method, h_max / Δ) of the FMU runs and (solver, h / Δ, tol) of the Exudyn runs
FMU_COSIM = (("rk4", 1.0), ("rk4", 0.25), ("rk8", 1.0), ("gauss4", 1.0), ("splitting", 1.0), ("exact_free", 1.0))
EXUDYN_COSIM = (
    ("RK44", 1.0, 1e-10),
    ("RK67", 1.0, 1e-10),
    ("DOPRI5", 1.0, 1e-10),
    ("TrapezoidalIndex2", 1.0, 1e-10),
    ("GeneralizedAlpha", 1.0, 1e-10),
)


def count_cosim_units(methods: Sequence[str]) -> int:
    """Progress units of the co-simulation part: reference, FMU runs (methods: the FMU's
    methods), Exudyn runs."""
    return 1 + len([m for m, _ in FMU_COSIM if m in methods]) + len(EXUDYN_COSIM)


def cosim_reference(sc: Scene, T: float, dt: float, delayed: bool = False) -> Reference:
    """DOP853 on the sampled-data loop (rtol 3e-14) with the same controller, its own
    error estimated by the same loop at rtol 3e-13; delayed: the loop with one sample of delay
    (OneSampleDelay), as ECOS and libcosim close it."""

    def ctrl() -> Any:
        return OneSampleDelay(cosim_controller()) if delayed else cosim_controller()

    tr = closed_loop_scipy(sc, ctrl(), T, dt, rtol=REF_RTOL, atol=REF_ATOL)
    tr12 = closed_loop_scipy(sc, ctrl(), T, dt, rtol=CHECK_RTOL, atol=CHECK_ATOL)
    ref = Reference(
        tr.time,
        tr.w_body,
        tr.q,
        f"scipy DOP853 sampled-data loop{' with one sample of delay' if delayed else ''}, rtol {REF_RTOL:g}",
        0.0,
        float(np.max(np.abs(tr.w_body))),
        tr.wall_time,
    )
    ref.floor = errors(tr12.w_body, tr12.q, ref)[2]
    return ref


def fmu_runs(
    fmu_path: Path, sc: Scene, T: float, dt: float, ref: Reference, c_ns: dict[str, float], progress: tqdm[Any] | None
) -> list[CosimRun]:
    """The FMU configurations of FMU_COSIM that the FMU has: median of 3 loops, compute
    median of 3 ctypes loops, C estimate = c_ns[method] (ns per internal step) × substeps."""
    runs: list[CosimRun] = []
    drv = FmuDriver(fmu_path, sc)
    try:
        for m, frac in FMU_COSIM:
            if m not in drv.method_values:
                continue
            h = dt * frac
            show(progress, f"co-simulation: FMU {m} h={h:g}")
            tot, ctl, out = fmu_cosim_once(drv, m, h, dt, T)
            reps = [(tot, ctl)] + [fmu_cosim_once(drv, m, h, dt, T)[:2] for _ in range(2)]
            tot = statistics.median(r[0] for r in reps)
            ctl = statistics.median(r[1] for r in reps)
            comp = statistics.median(fmu_compute(drv, m, h, dt, T) for _ in range(3))
            e_w, e_R, e = errors(out[None, 4:7], out[None, :4], ref)
            n_sub = round(T / dt) * max(1, math.ceil(1 / frac - 1e-9))
            est = c_ns.get(m, float("nan")) * 1e-9 * n_sub
            config = f"{m}, h_max = Δ/{1 / frac:g}" if frac != 1 else f"{m}, h_max = Δ"
            runs.append(CosimRun("FMU", config, tot, ctl, comp, tot - ctl - comp, e, e_w, e_R, est))
            advance(progress, f"co-simulation: FMU {m}")
    finally:
        drv.close()
    return runs


def exudyn_runs(
    sc: Scene, T: float, dt: float, ref: Reference, progress: tqdm[Any] | None, delayed: bool = False
) -> list[CosimRun]:
    """The Exudyn configurations of EXUDYN_COSIM, each in a guarded child process (an
    implicit solver may diverge); median of 3 runs below 0.5 s, else one. A failure is a
    run with NaN times, named in its configuration. delayed: the loop with one sample of delay."""
    runs: list[CosimRun] = []
    nan = float("nan")
    for solver, frac, tol in EXUDYN_COSIM:
        show(progress, f"co-simulation: Exudyn {solver}")
        try:
            reps = [guarded(_exudyn_cosim, sc, T, dt, solver, dt * frac, tol, delayed, timeout=max(30.0, 200 * T))]
            if reps[0][0].wall_time < 0.5:
                reps += [
                    guarded(_exudyn_cosim, sc, T, dt, solver, dt * frac, tol, delayed, timeout=max(30.0, 200 * T))
                    for _ in range(2)
                ]
        except Exception as exc:  # a failing configuration is a result, noted in the report
            runs.append(CosimRun("Exudyn", f"{solver}: failed ({exc})", nan, nan, nan, nan, nan, nan, nan))
            continue
        trx = reps[0][0]
        tot = statistics.median(r[0].wall_time for r in reps)
        ctl = statistics.median(r[1] for r in reps)
        e_w, e_R, e = errors(trx.w_body, trx.q, ref)
        cfgs = f"{solver}, tol = {tol:g}, h ≤ Δ" if solver == "DOPRI5" else f"{solver}, h = Δ"
        cpu = statistics.median(float(r[0].extra.get("cpu_time", nan)) for r in reps)
        runs.append(CosimRun("Exudyn", cfgs, tot, ctl, tot - ctl, 0.0, e, e_w, e_R, cpu=cpu))
        advance(progress, f"co-simulation: Exudyn {solver}")
    return runs


def min_cosim_speedup(runs: Sequence[CosimRun], ref: Reference) -> tuple[float | None, tuple[str, str] | None]:
    """The co-simulation target's measure: for every Exudyn configuration, the fastest FMU
    run at least as accurate (or within 3× the reference's own error); the smallest such
    speed-up and its (FMU, Exudyn) pair. (None, None) when no pair qualifies."""
    min_sp, pair = None, None
    fmu = [r for r in runs if r.tool == "FMU"]
    for ex in (r for r in runs if r.tool == "Exudyn" and math.isfinite(r.total)):
        ok = [r for r in fmu if r.err <= max(ex.err, 3 * ref.floor)]
        if not ok:
            continue
        best = min(ok, key=lambda r: r.total)
        sp = ex.total / best.total
        if min_sp is None or sp < min_sp:
            min_sp, pair = sp, (best.config, ex.config)
    return min_sp, pair


def cosim(fmu_path: Path, cfg: Config, c_ns: dict[str, float], progress: tqdm[Any] | None) -> CosimResult:
    """Closed-loop co-simulation of the torque-driven body at Δ = cfg.cosim_dt: the FMU through
    fmpy and Exudyn chunk by chunk, both with the same Python controller, against a DOP853
    sampled-data reference; wall time split into controller, tool compute and fmpy overhead."""
    sc = load_scene(cfg.cosim_scene)
    T, dt = cfg.cosim_T, cfg.cosim_dt
    ref = cosim_reference(sc, T, dt)
    advance(progress, "co-simulation: reference")
    runs = fmu_runs(fmu_path, sc, T, dt, ref, c_ns, progress) + exudyn_runs(sc, T, dt, ref, progress)
    min_sp, pair = min_cosim_speedup(runs, ref)
    return CosimResult(T, dt, ref, runs, min_sp, pair, c_ns)
