"""Batch mode of the report: every FMU method, Exudyn and scipy solver of a scene on its ladder; the batch target.

Batch mode: communication step T/comm_fraction, the inputs known in advance, so the
internal steps do the work. Each line runs its ladder cheapest first (`run_ladder`)
until its time cap, the error floor, or round-off stops it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from modelsrc.scene import Scene
from modelsrc.scene_inputs import Harmonic

from ..baselines.motion import integrate
from ..baselines.rigid_body import SCIPY_METHODS, Trajectory, comm_grid, run_exudyn
from ..exudyn.coverage import covers as exudyn_covers
from .config import EXUDYN_EXPLICIT, EXUDYN_IMPLICIT, LEVELS, TARGET_BATCH_SPEEDUP, Config, thin_ladder
from .harness import FmuDriver, advance, guarded, median_time, show
from .measures import LevelRow, Line, Point, fastest_table, nominal_steps
from .references import Reference, conserved_quantities, drifts, errors, make_reference
from .report_scenes import report_scene

if TYPE_CHECKING:
    from tqdm import tqdm


def predicted_wall(points: Sequence[Point], growth: float, least: float) -> float:
    """The wall time (s) the next rung of a ladder is predicted to take: the last rung's
    × the growth ratio of the last two (at least `least`), or × `growth` while fewer than
    two rungs have a wall time; 0 before the first rung."""
    if not points:
        return 0.0
    g = growth
    if len(points) >= 2 and points[-2].wall > 0:
        g = max(least, points[-1].wall / points[-2].wall)
    return points[-1].wall * g


def run_ladder(
    line: Line,
    rungs: Sequence[Any],
    run_one: Callable[[Any], Point],
    cap: float,
    floor: float,
    growth: float,
    progress: tqdm[Any] | None = None,
) -> Line:
    """Run rungs cheapest first until the next one is predicted to exceed `cap` s (the
    last wall time × the measured growth ratio of the last two rungs, at least half the
    nominal `growth`), the error is below `floor`, or it stopped improving (< 1.5× over two
    rungs that took > 1.5× the work and the time: round-off). A rung with a bit-identical
    result to the previous one is dropped. A failing rung is noted; two failures, or a
    timeout, end the line."""
    failures = 0
    for r in rungs:
        pts = line.points
        predicted = predicted_wall(pts, growth, growth * 0.5)
        if predicted > cap:
            line.notes.append(f"stopped before {r:.3g}: predicted {predicted:.2g} s > cap {cap:g} s")
            break
        show(progress, f"{line.name} {r:.3g}")
        try:
            p = run_one(r)
        except TimeoutError as exc:  # a finer rung would take longer still
            line.notes.append(f"{r:.3g}: {exc}; line ended")
            break
        except Exception as exc:  # a failing configuration is a result, noted in the report
            failures += 1
            line.notes.append(f"{r:.3g}: failed ({str(exc).splitlines()[0][:120]})")
            if failures >= 2:
                break
            continue
        if not (math.isfinite(p.err) and math.isfinite(p.wall)):
            line.notes.append(f"{r:.3g}: non-finite result (diverged)")
            failures += 1
            if failures >= 2:
                break
            continue
        pts = line.points
        if pts and p.e_w == pts[-1].e_w and p.e_R == pts[-1].e_R:
            # bit-identical final state: the same internal steps were taken, set by something
            # other than this parameter (the FMU's stiffness bound or Newton retry, a maximum
            # step); one point stands for both, and if it is the first, no coarser parameter
            # could do less work either
            line.notes.append(f"{r:.3g}: bit-identical to the previous rung (same internal steps), not plotted")
            if len(pts) == 1:
                line.min_work = pts[0].work if line.min_work is None else min(line.min_work, pts[0].work)
            continue
        pts.append(p)
        if p.err < floor:
            break
        if (
            len(pts) >= 3
            and pts[-1].err > pts[-3].err / 1.5
            and pts[-1].work > 1.5 * pts[-3].work
            and pts[-1].wall > 1.5 * pts[-3].wall
        ):
            # more work (nominal and timed), no better: round-off or the reference's floor
            line.notes.append(f"stopped after {r:.3g}: error no longer decreasing (round-off or reference floor)")
            break
    return line


def step_rungs(thetas: Sequence[float], omega: float, grid: np.ndarray) -> list[float]:
    """Internal steps h = θ/Ω (s) of a ladder, without rungs that split every interval
    into the same number of steps as the previous rung (h larger than the intervals)."""
    out: list[float] = []
    last = -1
    for th in thetas:
        h = th / omega
        n = nominal_steps(grid, h)
        if n != last:
            out.append(h)
            last = n
    return out


def exudyn_point(
    scene: Scene,
    grid_step: float,
    T: float,
    solver: str,
    h: float | None,
    tol: float,
    ref: Reference,
    cap: float,
    max_repeats: int,
) -> Point:
    """One Exudyn configuration: error, drift, median wall time. The implicit solvers and
    DOPRI5 run in a guarded child process: a diverging Newton iteration or a collapsing
    adaptive step cuts the step down without bound (measured: Exudyn's DOPRI5 at
    tol = 1e-12 on free_asymmetric ran for minutes)."""
    timeout = max(8.0, 4.0 * cap)

    def once() -> Trajectory:
        if scene.rotors:  # the jointed gyrostat (rbcheck.exudyn.rotors): implicit solvers only
            return guarded(run_exudyn_gyrostat, scene, grid_step, T, solver, float(h), timeout=timeout)
        if solver in EXUDYN_IMPLICIT or solver == "DOPRI5":
            return guarded(run_exudyn, scene, grid_step, T, solver, h=h, tol=tol, timeout=timeout)
        return run_exudyn(scene, grid_step, T, solver, h=h, tol=tol)

    tr = once()
    e_w, e_R, e = errors(tr.w_body, tr.q, ref, tr.extra.get("x_cm"))
    e_name, _ = conserved_quantities(scene)
    E = tr.extra[e_name] if e_name else None
    dE, dL, _ = drifts(scene, E, tr.extra["L_world"], None)

    wall = median_time(lambda: once().wall_time, tr.wall_time, max_repeats)
    label = f"tol={tol:.0e}" if solver == "DOPRI5" else f"h={h:.3g}"
    return Point(label, tol if solver == "DOPRI5" else float(h), wall, e, e_w, e_R, dE, dL, float("nan"), tr.n_steps)


def scipy_point(
    scene: Scene, grid: np.ndarray, method: str, rtol: float, atol: float, ref: Reference, max_repeats: int
) -> Point:
    """One scipy configuration: error, drift, median wall time."""
    tr = integrate(scene, grid, method, rtol=rtol, atol=atol, inputs="hold")  # as the FmuDriver (harness.py)
    e_w, e_R, e = errors(tr.w_body, tr.q, ref, tr.extra.get("x_cm"))
    inv = tr.extra["invariants"]
    e_name, _ = conserved_quantities(scene)
    dE, dL, dq = drifts(scene, inv[e_name] if e_name else None, inv["L_world"], inv["q_norm"])
    wall = median_time(
        lambda: integrate(scene, grid, method, rtol=rtol, atol=atol, inputs="hold").wall_time, tr.wall_time, max_repeats
    )
    return Point(f"rtol={rtol:.0e}", rtol, wall, e, e_w, e_R, dE, dL, dq, tr.nfev)


def run_exudyn_gyrostat(scene: Scene, grid_step: float, T: float, solver: str, h: float) -> Trajectory:
    """One run of the jointed Exudyn gyrostat (``rbcheck.exudyn.rotors.simulate_gyrostat``:
    each rotor a body on a revolute joint, the scene's schedules as the physical inputs) as
    a Trajectory; solver one of EXUDYN_IMPLICIT, h its fixed internal step (s); n_steps: the
    steps taken."""
    from ..exudyn.rotors import simulate_gyrostat  # imported here: exudyn is heavy to load

    res = simulate_gyrostat(scene, stop_time=T, step=grid_step, h=h, solver=solver)
    steps = sum(max(1, math.ceil((b - a) / h * (1.0 - 1e-12))) for a, b in zip(res["time"][:-1], res["time"][1:]))
    return Trajectory(
        time=res["time"],
        q=res["q"],
        w_body=res["w_body"],
        wall_time=float(res["wall_time"]),
        n_steps=int(steps),
        extra={k: res[k] for k in ("E_kin", "L_world", "x_cm") if k in res},
    )


def exudyn_rate(sc: Scene, ref: Reference) -> float:
    """Ω (rad/s) of the Exudyn step ladders θ = h·Ω: the reference's largest |ω|, or with
    rotors the fastest rotor's absolute rate, max |Ω| + max |ω| of the reference, if larger
    (the jointed model integrates each rotor's own rotation, ~100 rad/s on dual_spin against
    the hub's 1 rad/s, 110 rad/s on reaction_wheel_slew's wheels spun up from rest, 480 on
    quadrotor's propellers; the FMU and scipy carry only the rotor rates, so their ladders
    keep ref.omega_scale)."""
    return max(ref.omega_scale, ref.rotor_scale + ref.omega_scale if sc.rotors else 0.0)


def exudyn_missing(sc: Scene) -> str | None:
    """Why the scene has no Exudyn lines, or None: an Exudyn model must carry every torque
    and force of the scene, or it would simulate another system (rbcheck.exudyn.coverage:
    no orbit, central field or prescribed rate in the rigid-body models; rbcheck.exudyn.rotors.covers
    for the jointed gyrostat)."""
    if sc.rotors:
        from ..exudyn.rotors import covers as gyrostat_covers  # imported here: exudyn is heavy to load

        why = gyrostat_covers(sc)
        return None if why is None else f"the jointed Exudyn gyrostat does not cover it: {why}"
    return exudyn_covers(sc)


def exudyn_solvers(sc: Scene) -> tuple[str, ...]:
    """The Exudyn solvers of the scene's batch lines: none where no Exudyn model covers it
    (`exudyn_missing`: an orbit, docs/theory.md §9.6, a central field, a prescribed rate), the
    trapezoidal rule for the jointed gyrostat (its joints need an implicit solver, and
    generalized-α on its Lie-group nodes diverges at coarse steps: dual_spin's ω reached
    1.3e5 rad/s at h = 3.1e-4 s, θ = 2^-5), the implicit ones for a moving pivot (a joint),
    else all."""
    if exudyn_missing(sc) is not None:
        return ()
    if sc.rotors:
        return ("TrapezoidalIndex2",)
    if sc.has("moving_pivot"):
        return EXUDYN_IMPLICIT
    return EXUDYN_EXPLICIT + EXUDYN_IMPLICIT


def saturate_min_work(line: Line) -> Line:
    """Tolerance ladders: when the two loosest rungs did the same work, the step count is set
    by the communication intervals (the maximum step), not by the tolerance, and no looser
    tolerance can do less; the loosest rung is then the line's cheapest run (min_work)."""
    if len(line.points) >= 2 and line.points[0].work == line.points[1].work:
        line.min_work = line.points[0].work
    return line


@dataclass
class SceneResult:
    """Everything measured on one scene in batch mode."""

    name: str
    T: float
    step: float
    n_comm: int
    ref: Reference
    lines: list[Line]
    table: list[LevelRow]
    shortened: bool = False  # T shorter than the scene's stop time (Config.batch_stop_time)
    no_exudyn: str | None = None  # why there are no Exudyn lines (exudyn_missing), None where there are
    title: str = ""  # the scene's own name, where `name` (how it was asked for) is a scene file's path

    @property
    def label(self) -> str:
        """The scene's name in the report: its headings, its plot's file name."""
        return self.title or self.name


def fmu_lines(
    fmu_path: Path, sc: Scene, grid: np.ndarray, ref: Reference, cfg: Config, progress: tqdm[Any] | None
) -> list[Line]:
    """Every method of the scene's FMU on its h_max ladder (θ = h_max·Ω, cfg.fmu_theta)."""
    lines: list[Line] = []
    drv = FmuDriver(fmu_path, sc)
    try:
        for m in sc.methods:
            thetas = cfg.fmu_theta.get(m, cfg.fmu_theta_default)
            if not thetas:
                continue
            ln = Line(f"FMU {m}", "FMU", min_work=len(grid) - 1)
            run_ladder(
                ln,
                step_rungs(thetas, ref.omega_scale, grid),
                lambda h, m=m: drv.point(m, h, grid, ref, cfg.max_repeats),
                cfg.cap_fmu,
                cfg.floor,
                2.0,
                progress,
            )
            lines.append(ln)
            advance(progress, f"{sc.name}: {ln.name}")
    finally:
        drv.close()
    return lines


def exudyn_lines(
    sc: Scene, T: float, grid: np.ndarray, ref: Reference, cfg: Config, progress: tqdm[Any] | None
) -> list[Line]:
    """Exudyn's RK44/RK67 and implicit solvers on step ladders, DOPRI5 on a tolerance
    ladder (max step = the communication step T/cfg.comm_fraction, s). Gravity scenes:
    the explicit solvers on the "pivot" model, the implicit ones on the "joint" model
    (spherical joint), whose ladder starts at cfg.joint_theta_start."""
    H = batch_step(sc, cfg)
    gravity = sc.has("gravity") and not sc.has("translation")  # a top: "pivot" / "joint" models
    lines: list[Line] = []
    for solver in exudyn_solvers(sc):
        if solver == "DOPRI5":
            if not cfg.dopri_tol:
                continue
            ln = Line("Exudyn DOPRI5", "Exudyn")
            run_ladder(
                ln,
                cfg.dopri_tol,
                lambda tol: exudyn_point(sc, H, T, "DOPRI5", H, tol, ref, cfg.cap_exudyn, cfg.max_repeats),
                cfg.cap_exudyn,
                cfg.floor,
                1.3,
                progress,
            )
            saturate_min_work(ln)
        else:
            thetas = exudyn_ladder(solver, gravity, cfg)
            if not thetas:
                continue
            model = ("joint" if solver in EXUDYN_IMPLICIT else "pivot") if gravity else "free"
            if sc.moves:
                model = "shaker joint" if sc.has("moving_pivot") else "free body"
            if sc.rotors:
                model = "rotors on joints"
            ln = Line(
                f"Exudyn {solver}" + (f" ({model})" if gravity or sc.moves or sc.rotors else ""),
                "Exudyn",
                min_work=len(grid) - 1,
            )
            run_ladder(
                ln,
                step_rungs(thetas, exudyn_rate(sc, ref), grid),
                lambda h, s=solver: exudyn_point(sc, H, T, s, h, 1e-10, ref, cfg.cap_exudyn, cfg.max_repeats),
                cfg.cap_exudyn,
                cfg.floor,
                2.0,
                progress,
            )
        lines.append(ln)
        advance(progress, f"{sc.name}: {ln.name}")
    return lines


def exudyn_ladder(solver: str, gravity: bool, cfg: Config) -> tuple[float, ...]:
    """The θ rungs of an Exudyn step solver: cfg.exudyn_theta's, from cfg.joint_theta_start
    down for the implicit solvers on a top (gravity: the jointed model), then cut to
    cfg.short_rungs rungs in a short report (after the model's limit, so that the line
    starts at its coarsest usable step)."""
    thetas = cfg.exudyn_theta.get(solver, ())
    if solver in EXUDYN_IMPLICIT and gravity:
        thetas = tuple(th for th in thetas if th <= cfg.joint_theta_start)
    return thin_ladder(thetas, cfg.short_rungs) if cfg.short_rungs else tuple(thetas)


def scipy_lines(sc: Scene, grid: np.ndarray, ref: Reference, cfg: Config, progress: tqdm[Any] | None) -> list[Line]:
    """scipy's DOP853, Radau, LSODA on rtol ladders with atol = cfg.atol_factor·rtol."""
    lines: list[Line] = []
    for method in SCIPY_METHODS:
        rtols = cfg.scipy_rtol.get(method)
        if not rtols:
            continue
        ln = Line(f"scipy {method}", "scipy")
        run_ladder(
            ln,
            rtols,
            lambda rt, m=method: scipy_point(sc, grid, m, rt, cfg.atol_factor * rt, ref, cfg.max_repeats),
            cfg.cap_scipy,
            cfg.floor,
            1.3,
            progress,
        )
        saturate_min_work(ln)
        lines.append(ln)
        advance(progress, f"{sc.name}: {ln.name}")
    return lines


def batch_horizon(sc: Scene, cfg: Config) -> float:
    """Stop time (s) of batch mode: the scene's own, or cfg.batch_stop_time's where shorter
    (the short report's)."""
    return min(float(sc.stop_time), cfg.batch_stop_time.get(sc.name, math.inf))


def batch_step(sc: Scene, cfg: Config) -> float:
    """Communication step (s) of batch mode: T / cfg.comm_fraction (T: batch_horizon), at
    most a tenth of the period of a harmonic input (held at its mean over a step, it must be
    resolved, or the batch would simulate another system: the mean over T/10 of a 20 Hz
    shake is ~0)."""
    T = batch_horizon(sc, cfg)
    periods = [2.0 * math.pi / v.omega for v in sc.inputs.values() if isinstance(v, Harmonic)]
    return min([T / cfg.comm_fraction] + [0.1 * p for p in periods])


def batch_scene(name: str, fmu_path: Path, cfg: Config, progress: tqdm[Any] | None) -> SceneResult:
    """Batch mode on one scene (as `report_scene` gives it): every FMU method, Exudyn solver
    and scipy method on its ladder."""
    sc = report_scene(name)
    T = batch_horizon(sc, cfg)
    H = batch_step(sc, cfg)
    grid = comm_grid(sc, T, H)
    show(progress, f"{name}: reference")
    ref = make_reference(sc, grid)
    advance(progress, f"{name}: reference {ref.source}")
    lines = fmu_lines(fmu_path, sc, grid, ref, cfg, progress)
    lines += exudyn_lines(sc, T, grid, ref, cfg, progress)
    lines += scipy_lines(sc, grid, ref, cfg, progress)
    table = fastest_table(lines, LEVELS, ref.floor)
    return SceneResult(
        name, T, H, len(grid) - 1, ref, lines, table, float(sc.stop_time) > T, exudyn_missing(sc), sc.name
    )


def batch_units(cfg: Config, name: str, methods: Sequence[str]) -> int:
    """Progress units of one scene's batch: its reference and every line (methods: the FMU's)."""
    sc = report_scene(name)
    exudyn = [s for s in exudyn_solvers(sc) if (cfg.dopri_tol if s == "DOPRI5" else cfg.exudyn_theta.get(s))]
    scipy = [m for m in SCIPY_METHODS if cfg.scipy_rtol.get(m)]
    fmu = [m for m in methods if cfg.fmu_theta.get(m, cfg.fmu_theta_default)]
    return 1 + len(scipy) + len(exudyn) + len(fmu)


def count_batch_units(cfg: Config, methods: dict[str, Sequence[str]]) -> int:
    """Progress units of the batch part: reference + lines per scene (methods: scene ->
    the FMU's methods)."""
    return sum(batch_units(cfg, s, methods[s]) for s in cfg.scenes)


def batch_target(results: Sequence[SceneResult]) -> tuple[bool, list[str], list[str]]:
    """(met, failing cells, unverified cells) of the batch target: the best FMU line ≥ 10×
    faster than the best Exudyn and the best scipy line at every resolved level on every
    scene. Failing: speed-up < 10 or no FMU method at the level. Unverified: a speed-up
    ≥ 10 that is not a lower bound (the baseline's cheapest rung already met the level, so
    it might be faster still). Met only with neither."""
    fails: list[str] = []
    unverified: list[str] = []
    for res in results:
        for row in res.table:
            if not row.resolved:
                continue
            if row.fmu.time is None or row.fmu.lower_bound:
                fails.append(f"{res.label} {row.level:.0e}: no FMU method reached the level")
                continue
            for fam, other in (("Exudyn", row.exudyn), ("scipy", row.scipy)):
                if other.time is None:
                    continue
                sp = other.time / row.fmu.time
                if sp < TARGET_BATCH_SPEEDUP:
                    fails.append(
                        f"{res.label} {row.level:.0e}: {sp:.1f}× over {fam}"
                        + (" (lower bound)" if other.lower_bound or row.fmu.upper_bound else "")
                    )
                elif other.upper_bound and not other.lower_bound:
                    # the baseline's cheapest rung met the level: it might be faster still
                    unverified.append(f"{res.label} {row.level:.0e}: {sp:.0f}× over {fam}")
    return not fails and not unverified, fails, unverified


def min_batch_speedups(results: Sequence[SceneResult]) -> dict[str, tuple[float, str]]:
    """Smallest exact-or-bounded speed-up over each family across scenes and levels."""
    out: dict[str, tuple[float, str]] = {}
    for res in results:
        for row in res.table:
            if not row.resolved or row.fmu.time is None or row.fmu.lower_bound:
                continue
            for fam, other in (("Exudyn", row.exudyn), ("scipy", row.scipy)):
                if other.time is None:
                    continue
                sp = other.time / row.fmu.time
                if fam not in out or sp < out[fam][0]:
                    out[fam] = (sp, f"{res.label} at {row.level:.0e}")
    return out
