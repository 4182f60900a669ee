"""Work-precision report: error against run time of the FMU's integrators and of the
baselines (Exudyn, scipy), written to docs/report/report.md with PNG diagrams.

``python -c "from rbcheck.report import main; main()"`` (or ``rbfmu report``) regenerates
everything in one run; a text progress bar goes to stderr, the total time to stdout.

What is measured (the report repeats these definitions):

* error at the end time T of a run, against a reference: e_ω = ‖ω_run(T) − ω_ref(T)‖∞
  (rad/s, body frame), e_R = angle of R_runᵀ R_ref (rad, the geodesic distance on SO(3)),
  and the dimensionless headline error e = max(e_ω / Ω, e_R) with Ω = max_k ‖ω_ref(t_k)‖∞
  over the communication points (rad/s);
* invariant drift, maximum over the communication points: relative E (E_kin of a free
  body, E_total of the heavy top), relative |L_world| (free body) or L_world·e_z (heavy
  top: p_φ, docs/theory.md §4.2), and ||q| − 1|;
* wall time of the integration loop only (no FMU loading, no model assembly), median of
  repeats taken in the same run.

References (docs/theory.md §2.3, §4.2): the closed forms of rbcheck.free_symmetric,
rbcheck.free_asymmetric, rbcheck.heavy_top where they apply, else scipy DOP853 at
rtol = 3e-14, atol = 1e-16 on the numpy equations of rbcheck.baselines.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import statistics
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from . import free_asymmetric, free_symmetric, heavy_top
from .baselines import (
    SCIPY_METHODS,
    AttitudePD,
    Trajectory,
    closed_loop_scipy,
    comm_grid,
    integrate_scipy,
    run_exudyn,
    scene_has,
    table_value,
)
from .rotation_np import quat_from_axis_angle, quat_to_matrix, rotation_angle_between

REPO = Path(__file__).resolve().parent.parent
DEFAULT_OUT = REPO / "docs" / "report"
DEFAULT_SCENES = ("symmetric_free", "free_asymmetric", "heavy_top", "sleeping_top", "torque_driven")
LEVELS = tuple(10.0**-k for k in range(4, 12))  # error levels of the table, 1e-4 ... 1e-11
ERR_FLOOR = 1e-17  # errors are clamped here before taking logs (exact agreement happens)
EXUDYN_EXPLICIT = ("RK44", "RK67", "DOPRI5")
EXUDYN_IMPLICIT = ("TrapezoidalIndex2", "GeneralizedAlpha")

# Targets of the issue
TARGET_STEP_RATIO = 1.2  # internal step through fmi3DoStep <= 1.2 x the raw generated step
TARGET_BATCH_SPEEDUP = 10.0
TARGET_COSIM_SPEEDUP = 50.0


# ----------------------------------------------------------------------------------
# configuration
# ----------------------------------------------------------------------------------
def _pow2(a: int, b: int) -> tuple[float, ...]:
    """2^-a, 2^-(a+1), ..., 2^-b (a may be negative: coarser than 1)."""
    return tuple(2.0**-k for k in range(a, b + 1))


@dataclass
class Config:
    """Ladders, time caps and problem sizes of one report run.

    Step ladders are in θ = h·Ω (dimensionless rotation per internal step, Ω the scene's
    largest |ω|, rad/s), so one ladder serves a top at 150 rad/s and a body at 1 rad/s.
    A ladder stops early when its next rung is predicted to take more than the family's
    cap (s), when the error has reached `floor`, or when it stopped decreasing (round-off).
    """

    scenes: tuple[str, ...] = DEFAULT_SCENES
    comm_fraction: int = 10  # batch mode: communication step T/10
    fmu_theta: dict[str, tuple[float, ...]] = field(
        default_factory=lambda: {
            "rk4": _pow2(1, 12),
            "rk8": _pow2(-1, 8),
            "implicit_midpoint": _pow2(2, 16),
            "gauss4": _pow2(1, 10),
            "gauss6": _pow2(-1, 8),
            "splitting": _pow2(2, 16),
            # exact for a torque-free body at any step, order 2 (kick - flow - kick) with torques
            "exact_free": _pow2(-1, 16),
        }
    )
    # ladder of a method the FMU has but fmu_theta does not name (None: skip such methods)
    fmu_theta_default: tuple[float, ...] | None = _pow2(1, 14)
    exudyn_theta: dict[str, tuple[float, ...]] = field(
        default_factory=lambda: {
            "RK44": _pow2(1, 12),
            "RK67": _pow2(-1, 10),
            "TrapezoidalIndex2": _pow2(3, 16),
            "GeneralizedAlpha": _pow2(3, 16),
        }
    )
    # Exudyn's generalized-α on the jointed top diverges for h·ω ≥ 0.015 (measured on
    # heavy_top, 1.13.6: 9e5 steps and ω = 1.6e5 rad/s at h = 1e-4 s), so the jointed
    # model's implicit ladders start at θ = 2^-7.
    joint_theta_start: float = 2.0**-7
    dopri_tol: tuple[float, ...] = tuple(10.0**-k for k in range(1, 14))
    scipy_rtol: dict[str, tuple[float, ...]] = field(
        default_factory=lambda: {
            "DOP853": tuple(10.0**-k for k in range(1, 14)),
            "Radau": tuple(10.0**-k for k in range(1, 12)),
            "LSODA": tuple(10.0**-k for k in range(1, 14)),
        }
    )
    atol_factor: float = 1e-3  # scipy: atol = 1e-3 · rtol, on every state (q is O(1), ω in rad/s)
    cap_fmu: float = 1.0
    cap_exudyn: float = 2.0
    cap_scipy: float = 2.0
    floor: float = 3e-13
    max_repeats: int = 5
    # co-simulation
    cosim_scene: str = "torque_driven"
    cosim_dt: float = 1e-3
    cosim_T: float = 4.0
    # long horizon
    long_scene: str = "free_asymmetric"
    long_steps: int = 10_000_000
    long_budget: float = 10.0  # s: a method whose projected full run exceeds this stops at its first tenth
    long_chunks: int = 100
    # C step cost
    bench_scenes: tuple[str, ...] = ("free_asymmetric", "heavy_top", "torque_driven")
    bench_n_explicit: int = 200_000
    bench_n_implicit: int = 5_000

    @staticmethod
    def quick(scenes: Sequence[str] = ("symmetric_free",)) -> "Config":
        """A tiny configuration for smoke tests: seconds, not minutes."""
        return Config(
            scenes=tuple(scenes),
            fmu_theta={"rk4": _pow2(2, 4), "gauss4": _pow2(2, 3)},
            fmu_theta_default=None,
            exudyn_theta={"RK44": _pow2(2, 3)},
            dopri_tol=(1e-6,),
            scipy_rtol={"DOP853": (1e-6, 1e-8)},
            cap_fmu=0.2,
            cap_exudyn=0.5,
            cap_scipy=0.5,
            max_repeats=2,
            cosim_T=0.1,
            long_steps=100_000,
            long_budget=0.05,
            long_chunks=10,
            bench_scenes=(),
            bench_n_explicit=20_000,
            bench_n_implicit=2_000,
        )


# ----------------------------------------------------------------------------------
# results
# ----------------------------------------------------------------------------------
@dataclass
class Point:
    """One run of a line: its parameter, cost and accuracy (see the module docstring)."""

    param: str
    value: float
    wall: float
    err: float
    e_w: float
    e_R: float
    drift_E: float = float("nan")
    drift_L: float = float("nan")
    drift_q: float = float("nan")
    work: int = 0  # internal steps (FMU, Exudyn) or right-hand-side calls (scipy)


@dataclass
class Line:
    """One method/solver of one family ("FMU", "Exudyn", "scipy") over its ladder."""

    name: str
    family: str
    points: list[Point] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    # least work any configuration of the line can do (fixed-step ladders: one step per
    # communication interval); a first rung at it is the line's cheapest possible run
    min_work: int | None = None


def time_at_level(points: Sequence[tuple[float, float]], level: float) -> tuple[float, bool] | None:
    """(wall time s, at_first_rung) at which a line first reaches error ≤ level, the time
    interpolated linearly in log(time)–log(error) between the two rungs around the crossing
    (ladder order, cheapest first). None when no rung reaches the level. When the first
    rung already does, its time is returned with at_first_rung = True: an upper bound,
    since a coarser rung might have been cheaper."""
    if not level > 0:
        raise ValueError(f"error level must be > 0, got {level}")
    prev: tuple[float, float] | None = None
    for t, e in points:
        e = max(e, ERR_FLOOR)
        if e <= level:
            if prev is None:
                return t, True
            t0, e0 = prev
            f = (math.log(e0) - math.log(level)) / (math.log(e0) - math.log(e))
            return math.exp(math.log(t0) + f * (math.log(t) - math.log(t0))), False
        if math.isfinite(e):
            prev = (t, e)
    return None


@dataclass
class Best:
    """Fastest line of a family at one error level: time (s), and whether it is only a
    lower bound (no line of the family got there cheaper than the cheapest of the
    unfinished lines' most expensive runs) or an upper bound (the winning line's
    cheapest rung already met the level)."""

    line: str | None
    time: float | None
    lower_bound: bool = False
    upper_bound: bool = False


def best_of(lines: Iterable[Line], level: float) -> Best:
    """The fastest line at `level` among `lines`, or a lower bound on any line's time.

    A line that stops above the level would need more than its most expensive run to get
    there (cost grows along a ladder), so min over such lines of their largest time bounds
    what they could achieve; if that is below every reached time the result is a bound.
    A line whose first rung meets the level gives an upper bound, unless that rung is the
    least work the line can do (`Line.min_work`)."""
    reached: list[tuple[float, bool, str]] = []
    bounds: list[tuple[float, str]] = []
    for ln in lines:
        pts = [(p.wall, p.err) for p in ln.points]
        if not pts:
            continue
        hit = time_at_level(pts, level)
        if hit is None:
            bounds.append((max(p.wall for p in ln.points), ln.name))
        else:
            cheapest = ln.min_work is not None and ln.points[0].work <= ln.min_work
            reached.append((hit[0], hit[1] and not cheapest, ln.name))
    if reached:
        t, first, name = min(reached)
        if bounds and min(bounds)[0] < t:
            return Best(name, min(bounds)[0], lower_bound=True)
        return Best(name, t, upper_bound=first)
    if bounds:
        return Best(None, min(bounds)[0], lower_bound=True)
    return Best(None, None)


@dataclass
class LevelRow:
    """One row of the fastest-method table: the level, the overall fastest line, the best
    of each family and the FMU's speed-ups (None where undefined; `*_bound` True when the
    speed-up is a lower bound because the baseline never reached the level)."""

    level: float
    fastest: str | None
    fastest_time: float | None
    fmu: Best
    exudyn: Best
    scipy: Best
    speedup_exudyn: float | None
    speedup_scipy: float | None
    resolved: bool = True


def fastest_table(lines: Sequence[Line], levels: Sequence[float] = LEVELS, ref_floor: float = 0.0) -> list[LevelRow]:
    """For each error level: the fastest line (interpolated along each line) and the best
    FMU line's speed-up over the best Exudyn and the best scipy line. A level below 3× the
    reference's own error estimate `ref_floor` is marked unresolved."""
    rows = []
    fam = {f: [ln for ln in lines if ln.family == f] for f in ("FMU", "Exudyn", "scipy")}
    for lev in levels:
        b = {f: best_of(fam[f], lev) for f in fam}
        overall = [(bb.time, bb.line) for bb in b.values() if bb.line is not None and not bb.lower_bound]
        fastest = min(overall) if overall else (None, None)

        def ratio(other: Best) -> float | None:
            if b["FMU"].time is None or b["FMU"].lower_bound or other.time is None or other.upper_bound:
                return None  # undefined, or a bound in the wrong direction
            return other.time / b["FMU"].time

        rows.append(
            LevelRow(
                lev,
                fastest[1],
                fastest[0],
                b["FMU"],
                b["Exudyn"],
                b["scipy"],
                ratio(b["Exudyn"]),
                ratio(b["scipy"]),
                resolved=lev >= 3.0 * ref_floor,
            )
        )
    return rows


def observed_order(h: Sequence[float], err: Sequence[float]) -> float:
    """Least-squares slope of log(err) against log(h): the observed order of convergence."""
    x, y = np.log(np.asarray(h, float)), np.log(np.maximum(np.asarray(err, float), ERR_FLOOR))
    if x.size < 2:
        raise ValueError(f"need at least two (h, error) pairs for an order, got {x.size}")
    return float(np.polyfit(x, y, 1)[0])


def asymptotic_order(points: Sequence[Point], low: float, high: float = 1e-2) -> float | None:
    """Median of the local slopes log(e_i/e_j)/log(h_i/h_j) between consecutive rungs whose
    errors both lie in [low, high] (above round-off and the reference floor, below the
    pre-asymptotic range) and whose wall time grew ≥ 1.5× (the step really shrank: the FMU's
    explicit methods may take more substeps than h_max asks, by their stiffness bound, and
    tiny runs are overhead). None with no such pair."""
    slopes = [
        math.log(a.err / b.err) / math.log(a.value / b.value)
        for a, b in zip(points[:-1], points[1:])
        if low <= b.err and a.err <= high and a.value != b.value and b.wall >= 1.5 * a.wall
    ]
    return float(np.median(slopes)) if slopes else None


# ----------------------------------------------------------------------------------
# references and error measures
# ----------------------------------------------------------------------------------
@dataclass
class Reference:
    """Reference states at the communication points: w (n,3) rad/s body, q (n,4);
    `source` names it; `floor` estimates its own headline error (dimensionless)."""

    time: np.ndarray
    w: np.ndarray
    q: np.ndarray
    source: str
    floor: float
    omega_scale: float
    wall: float


def _free(scene: Any) -> bool:
    return not (scene.features & {"torque_body", "torque_world", "gravity", "friction"})


def closed_form(scene: Any, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, str] | None:
    """Closed-form (w, q, name) at times t where one applies (docs/theory.md §2.3, §4.2):
    torque-free symmetric (I1 = I2) or asymmetric principal body, or the Lagrange top
    (I1 = I2 about the centre of mass, r_cm on e3 above the pivot, g along −e_z, no
    friction, no torque inputs). None otherwise."""
    I = np.asarray(scene.inertia, dtype=float)
    if not np.allclose(I, np.diag(np.diag(I)), rtol=0, atol=1e-15 * np.abs(I).max()):
        return None
    d = np.diag(I)
    if _free(scene):
        if d[0] == d[1]:
            w, q = free_symmetric.solve(d[0], d[2], scene.w0, scene.q0, t)
            return w, q, "closed form rbcheck.free_symmetric"
        if len(set(d.tolist())) == 3:
            w, q = free_asymmetric.solve(d, scene.w0, scene.q0, t)
            return w, q, "closed form rbcheck.free_asymmetric"
        return None
    if scene.features == frozenset({"gravity"}) and d[0] == d[1]:
        r, g = np.asarray(scene.r_cm, float), np.asarray(scene.g, float)
        if r[0] == r[1] == 0 and r[2] > 0 and g[0] == g[1] == 0 and g[2] < 0:
            l, M = float(r[2]), float(scene.mass)
            # transverse moment about the pivot (parallel-axis theorem, docs/theory.md §3.2)
            P = heavy_top.TopParams(I1=d[0] + M * l * l, I3=d[2], M=M, g=-float(g[2]), l=l)
            top = heavy_top.HeavyTop(P, heavy_top.init_from_state(scene.q0, scene.w0))
            return top.omega(t), top.quaternion(t), "closed form rbcheck.heavy_top"
    return None


def errors(w: np.ndarray, q: np.ndarray, ref: Reference) -> tuple[float, float, float]:
    """(e_ω rad/s, e_R rad, headline e) at the last communication point."""
    e_w = float(np.max(np.abs(np.asarray(w)[-1] - ref.w[-1])))
    e_R = float(rotation_angle_between(quat_to_matrix(np.asarray(q)[-1]), quat_to_matrix(ref.q[-1])))
    return e_w, e_R, max(e_w / ref.omega_scale, e_R)


REF_RTOL, REF_ATOL = 3e-14, 1e-16  # scipy refuses rtol < 100 eps = 2.2e-14
CHECK_RTOL, CHECK_ATOL = 3e-13, 1e-15


def make_reference(scene: Any, grid: np.ndarray) -> Reference:
    """The scene's reference at the grid points, with an estimate of its own error:
    for a closed form, its distance to DOP853 at rtol 3e-14; for DOP853 at rtol 3e-14,
    its distance to DOP853 at rtol 3e-13 (an over-estimate: DOP853's error scales about
    linearly with rtol, so the finer run is ~10x better than this difference)."""
    tic = time.perf_counter()
    cf = closed_form(scene, grid)
    fine = integrate_scipy(scene, grid, "DOP853", rtol=REF_RTOL, atol=REF_ATOL)
    if cf is not None:
        w, q, src = cf
        other_w, other_q = fine.w_body, fine.q
    else:
        coarse = integrate_scipy(scene, grid, "DOP853", rtol=CHECK_RTOL, atol=CHECK_ATOL)
        w, q, src = fine.w_body, fine.q, f"scipy DOP853, rtol {REF_RTOL:g}, atol {REF_ATOL:g}"
        other_w, other_q = coarse.w_body, coarse.q
    omega = float(np.max(np.abs(w)))
    if not omega > 0:
        raise ValueError(f"scene {scene.name}: the reference never rotates (max |ω| = 0), no error scale")
    ref = Reference(np.asarray(grid, float), np.asarray(w), np.asarray(q), src, 0.0, omega, 0.0)
    ref.floor = errors(other_w, other_q, ref)[2]
    ref.wall = time.perf_counter() - tic
    return ref


def conserved_quantities(scene: Any) -> tuple[str | None, str | None]:
    """(energy output, momentum measure) the scene conserves: ("E_kin", "|L|") for a free
    body, ("E_total", "Lz") for a frictionless top on a pivot (p_φ = L_world·e_z, §4.2),
    (None, None) when torques or friction act."""
    if _free(scene):
        return "E_kin", "|L|"
    if scene.features == frozenset({"gravity"}) and np.allclose(np.asarray(scene.g)[:2], 0):
        return "E_total", "Lz"
    return None, None


def drifts(scene: Any, E: np.ndarray | None, L: np.ndarray | None, qn: np.ndarray | None) -> tuple[float, float, float]:
    """(relative E drift, relative L drift, max ||q| − 1|) over the samples; NaN if n/a."""
    e_name, l_name = conserved_quantities(scene)
    dE = dL = dq = float("nan")
    if e_name and E is not None:
        dE = float(np.max(np.abs(E - E[0])) / abs(E[0]))
    if l_name and L is not None:
        L = np.asarray(L)
        if l_name == "|L|":
            n = np.linalg.norm(L, axis=1)
            dL = float(np.max(np.abs(n - n[0])) / n[0])
        else:
            dL = float(np.max(np.abs(L[:, 2] - L[0, 2])) / np.linalg.norm(L[0]))
    if qn is not None:
        dq = float(np.max(np.abs(np.asarray(qn) - 1.0)))
    return dE, dL, dq


# ----------------------------------------------------------------------------------
# timing helpers
# ----------------------------------------------------------------------------------
def median_time(fn: Callable[[], float], first: float, max_repeats: int) -> float:
    """Median of `first` (a timing already taken) and further timings by fn(), repeated
    more often the cheaper a run is: 5 below 20 ms, 3 below 0.2 s, else just `first`."""
    n = 1 if first >= 0.2 else (3 if first >= 0.02 else 5)
    times = [first] + [fn() for _ in range(min(n, max_repeats) - 1)]
    return float(statistics.median(times))


def _guard_child(conn, fn, args, kwargs):  # pragma: no cover - runs in the forked child
    try:
        conn.send(("ok", fn(*args, **kwargs)))
    except BaseException as exc:  # noqa: BLE001 - report anything to the parent
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


def guarded(fn: Callable[..., Any], *args: Any, timeout: float, **kwargs: Any) -> Any:
    """fn(*args, **kwargs) in a forked child killed after `timeout` s (an Exudyn implicit
    solver that diverges cuts its step down and can run for minutes; C code cannot be
    interrupted from a thread). Raises TimeoutError or RuntimeError with the child's error."""
    ctx = multiprocessing.get_context("fork")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_guard_child, args=(send, fn, args, kwargs), daemon=True)
    proc.start()
    send.close()
    try:
        if not recv.poll(timeout):
            raise TimeoutError(f"no result within {timeout:.0f} s")
        status, value = recv.recv()
    except EOFError:
        status, value = "error", f"the child process died (exit code {proc.exitcode})"
    finally:
        if proc.is_alive():
            proc.kill()
        proc.join()
        recv.close()
    if status != "ok":
        raise RuntimeError(value)
    return value


class Progress:
    """A one-line text progress bar on stderr: [#####.....] k/n what."""

    def __init__(self, total: int, stream=None, width: int = 30):
        self.total, self.done, self.width = max(1, total), 0, width
        self.stream = sys.stderr if stream is None else stream
        self.t0 = time.perf_counter()

    def show(self, what: str) -> None:
        f = min(1.0, self.done / self.total)
        bar = "#" * int(round(f * self.width))
        line = f"[{bar:<{self.width}}] {self.done}/{self.total} {time.perf_counter() - self.t0:6.0f} s  {what}"
        self.stream.write("\r" + line[:110].ljust(110))
        self.stream.flush()

    def advance(self, what: str = "") -> None:
        self.done += 1
        self.show(what)

    def finish(self) -> None:
        self.stream.write("\n")
        self.stream.flush()


# ----------------------------------------------------------------------------------
# the FMU side
# ----------------------------------------------------------------------------------
class FmuDriver:
    """One scene's FMU, instantiated once and reset between runs (fmi3Reset), stepped
    through fmpy. Runs a communication grid with the scene's input tables held per step."""

    def __init__(self, fmu_path: Path, scene: Any):
        from fmu.run import FmuInstance

        self.scene = scene
        self.inst = FmuInstance(fmu_path)
        md = self.inst.md
        enum = {t.name: t for t in md.typeDefinitions}
        mvar = self.inst.variables["method"]
        self.method_values = (
            {i.name: int(i.value) for i in enum[mvar.declaredType.name].items} if mvar.declaredType is not None else {}
        )
        names = set(self.inst.vr)
        self.inputs = [b for b in ("tau_body", "tau_world") if f"{b}[1]" in names]
        e_name, _ = conserved_quantities(scene)
        self.out_names = [f"q[{k}]" for k in range(1, 5)] + [f"w_body[{k}]" for k in range(1, 4)]
        self.has_E = e_name is not None and e_name in names
        if self.has_E:
            self.out_names.append(e_name)
        self.has_L = "L_world[1]" in names
        if self.has_L:
            self.out_names += [f"L_world[{k}]" for k in range(1, 4)]
        self.out_vrs = self.inst._vrs(self.out_names)
        self.in_vrs = {b: self.inst._vrs([f"{b}[{k}]" for k in range(1, 4)]) for b in self.inputs}

    def close(self) -> None:
        self.inst.close()

    def start(self, method: str, h_max: float, stop_time: float) -> None:
        """Reset, choose the method and h_max (s), initialise for [0, stop_time]."""
        if method not in self.method_values:
            raise ValueError(f"method {method!r} is not in this FMU; it has {sorted(self.method_values)}")
        self.inst.fmu.reset()
        self.inst.set({"method": self.method_values[method], "h_max": float(h_max)})
        self.inst.initialize(0.0, stop_time)

    def input_schedule(self, grid: np.ndarray) -> list[list[float] | None]:
        """Per communication interval: the input values (N·m; tau_body then tau_world) from
        the scene's tables, or None when they equal the previous interval's. In batch mode
        the schedule is known in advance, and an input keeps its value until set again
        (FMI 3.0), so the master sets inputs only when a table switches."""
        out: list[list[float] | None] = []
        prev = None
        for t in grid[:-1]:
            u = [
                float(x)
                for b in self.inputs
                for x in (table_value(self.scene.inputs[b], float(t)) if b in self.scene.inputs else (0.0, 0.0, 0.0))
            ]
            out.append(None if u == prev else u)
            prev = u
        return out

    def run(self, method: str, h_max: float, grid: np.ndarray, record: bool) -> tuple[float, np.ndarray | None]:
        """Step over the grid; returns (wall s of the stepping loop, outputs (n, k) or None)."""
        sched = self.input_schedule(grid) if self.inputs else [None] * (len(grid) - 1)
        in_vrs = [v for b in self.inputs for v in self.in_vrs[b]]
        steps = [(float(a), float(b - a), u) for a, b, u in zip(grid[:-1], grid[1:], sched)]
        self.start(method, h_max, float(grid[-1]))
        do, get, setf = self.inst.fmu.doStep, self.inst.fmu.getFloat64, self.inst.fmu.setFloat64
        rows = [get(self.out_vrs)] if record else None
        tic = time.perf_counter()
        for t0, dt, u in steps:
            if u is not None:
                setf(in_vrs, u)
            do(t0, dt)
            if record:
                rows.append(get(self.out_vrs))
        wall = time.perf_counter() - tic
        return wall, (np.array(rows) if record else None)

    def point(self, method: str, h_max: float, grid: np.ndarray, ref: Reference, max_repeats: int) -> Point:
        """Error, drift (recording run) and median wall time (runs without output reads)."""
        _, Y = self.run(method, h_max, grid, record=True)
        e_w, e_R, e = errors(Y[:, 4:7], Y[:, :4], ref)
        k = 7
        E = Y[:, k] if self.has_E else None
        k += int(self.has_E)
        L = Y[:, k : k + 3] if self.has_L else None
        dE, dL, dq = drifts(self.scene, E, L, np.linalg.norm(Y[:, :4], axis=1))
        first = self.run(method, h_max, grid, record=False)[0]
        wall = median_time(lambda: self.run(method, h_max, grid, record=False)[0], first, max_repeats)
        return Point(f"h={h_max:.3g}", h_max, wall, e, e_w, e_R, dE, dL, dq, nominal_steps(grid, h_max))


# ----------------------------------------------------------------------------------
# ladders
# ----------------------------------------------------------------------------------
def run_ladder(
    line: Line,
    rungs: Sequence[Any],
    run_one: Callable[[Any], Point],
    cap: float,
    floor: float,
    growth: float,
    progress: Progress | None = None,
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
        if pts:
            g = growth
            if len(pts) >= 2 and pts[-2].wall > 0:
                g = max(growth * 0.5, pts[-1].wall / pts[-2].wall)
            if pts[-1].wall * g > cap:
                line.notes.append(f"stopped before {r:.3g}: predicted {pts[-1].wall * g:.2g} s > cap {cap:g} s")
                break
        if progress:
            progress.show(f"{line.name} {r:.3g}")
        try:
            p = run_one(r)
        except TimeoutError as exc:  # a finer rung would take longer still
            line.notes.append(f"{r:.3g}: {exc}; line ended")
            break
        except Exception as exc:  # noqa: BLE001 - a failing configuration is a result, noted in the report
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


def nominal_steps(grid: np.ndarray, h: float) -> int:
    """Internal steps ⌈Δ_k/h⌉ summed over the communication intervals Δ_k (s), as the FMU
    (without its stiffness bound) and Exudyn's driver split them."""
    return int(sum(math.ceil((b - a) / h * (1 - 1e-12)) for a, b in zip(grid[:-1], grid[1:])))


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
    scene: Any,
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
        if solver in EXUDYN_IMPLICIT or solver == "DOPRI5":
            return guarded(run_exudyn, scene, grid_step, T, solver, h=h, tol=tol, timeout=timeout)
        return run_exudyn(scene, grid_step, T, solver, h=h, tol=tol)

    tr = once()
    e_w, e_R, e = errors(tr.w_body, tr.q, ref)
    e_name, _ = conserved_quantities(scene)
    E = tr.extra[e_name] if e_name else None
    dE, dL, _ = drifts(scene, E, tr.extra["L_world"], None)

    wall = median_time(lambda: once().wall_time, tr.wall_time, max_repeats)
    label = f"tol={tol:.0e}" if solver == "DOPRI5" else f"h={h:.3g}"
    return Point(label, tol if solver == "DOPRI5" else float(h), wall, e, e_w, e_R, dE, dL, float("nan"), tr.n_steps)


def scipy_point(
    scene: Any, grid: np.ndarray, method: str, rtol: float, atol: float, ref: Reference, max_repeats: int
) -> Point:
    """One scipy configuration: error, drift, median wall time."""
    tr = integrate_scipy(scene, grid, method, rtol=rtol, atol=atol)
    e_w, e_R, e = errors(tr.w_body, tr.q, ref)
    inv = tr.extra["invariants"]
    e_name, _ = conserved_quantities(scene)
    dE, dL, dq = drifts(scene, inv[e_name] if e_name else None, inv["L_world"], inv["q_norm"])
    wall = median_time(
        lambda: integrate_scipy(scene, grid, method, rtol=rtol, atol=atol).wall_time, tr.wall_time, max_repeats
    )
    return Point(f"rtol={rtol:.0e}", rtol, wall, e, e_w, e_R, dE, dL, dq, tr.nfev)


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


def batch_scene(name: str, fmu_path: Path, cfg: Config, progress: Progress | None) -> SceneResult:
    """Batch mode on one scene: every FMU method, Exudyn solver and scipy method on its ladder."""
    from modelsrc.scene import load_scene

    sc = load_scene(name)
    T = float(sc.stop_time)
    H = T / cfg.comm_fraction
    grid = comm_grid(sc, T, H)
    if progress:
        progress.show(f"{name}: reference")
    ref = make_reference(sc, grid)
    if progress:
        progress.advance(f"{name}: reference {ref.source}")
    W = ref.omega_scale
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
                step_rungs(thetas, W, grid),
                lambda h, m=m: drv.point(m, h, grid, ref, cfg.max_repeats),
                cfg.cap_fmu,
                cfg.floor,
                2.0,
                progress,
            )
            lines.append(ln)
            if progress:
                progress.advance(f"{name}: {ln.name}")
    finally:
        drv.close()
    gravity = scene_has(sc, "gravity")
    for solver in EXPLICIT_ORDER + EXUDYN_IMPLICIT:
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
            thetas = cfg.exudyn_theta.get(solver)
            if not thetas:
                continue
            if solver in EXUDYN_IMPLICIT and gravity:
                thetas = tuple(th for th in thetas if th <= cfg.joint_theta_start)
            model = ("joint" if solver in EXUDYN_IMPLICIT else "pivot") if gravity else "free"
            ln = Line(f"Exudyn {solver}" + (f" ({model})" if gravity else ""), "Exudyn", min_work=len(grid) - 1)
            run_ladder(
                ln,
                step_rungs(thetas, W, grid),
                lambda h, s=solver: exudyn_point(sc, H, T, s, h, 1e-10, ref, cfg.cap_exudyn, cfg.max_repeats),
                cfg.cap_exudyn,
                cfg.floor,
                2.0,
                progress,
            )
        lines.append(ln)
        if progress:
            progress.advance(f"{name}: {ln.name}")
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
        if progress:
            progress.advance(f"{name}: {ln.name}")
    return SceneResult(name, T, H, len(grid) - 1, ref, lines, fastest_table(lines, LEVELS, ref.floor))


EXPLICIT_ORDER = EXUDYN_EXPLICIT


def saturate_min_work(line: Line) -> Line:
    """Tolerance ladders: when the two loosest rungs did the same work, the step count is set
    by the communication intervals (the maximum step), not by the tolerance, and no looser
    tolerance can do less; the loosest rung is then the line's cheapest run (min_work)."""
    if len(line.points) >= 2 and line.points[0].work == line.points[1].work:
        line.min_work = line.points[0].work
    return line


def count_batch_units(cfg: Config, methods: dict[str, Sequence[str]]) -> int:
    """Progress units of the batch part: reference + lines per scene (methods: scene ->
    the FMU's methods)."""
    per = (
        1
        + len([s for s in EXUDYN_EXPLICIT if s != "DOPRI5" and cfg.exudyn_theta.get(s)])
        + (1 if cfg.dopri_tol else 0)
        + len([s for s in EXUDYN_IMPLICIT if cfg.exudyn_theta.get(s)])
        + len([m for m in SCIPY_METHODS if cfg.scipy_rtol.get(m)])
    )
    return sum(per + len([m for m in methods[s] if cfg.fmu_theta.get(m, cfg.fmu_theta_default)]) for s in cfg.scenes)


# ----------------------------------------------------------------------------------
# C step cost (extends fmu.benchmark.c_step_ns to every method)
# ----------------------------------------------------------------------------------
def c_step_ns_all(fmu: Path, n_explicit: int, n_implicit: int) -> dict[str, tuple[float, float]]:
    """method -> (raw generated step ns, through fmi3DoStep ns per internal step), with the
    benchmark harness fmu/c/bench_step.c compiled once against the FMU's sources and run
    per method index (its second argument). Best of 5 inside the harness."""
    from fmu.benchmark import HARNESS
    from fmu.build_fmu import CFLAGS, GENERATED_EXTRA

    out: dict[str, tuple[float, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        with zipfile.ZipFile(fmu) as z:
            z.extractall(tmp)
        src = Path(tmp) / "sources"
        header = (src / "model_data.h").read_text()
        names_line = next(ln for ln in header.splitlines() if "rb_method_names" in ln and "{" in ln)
        names = [s.strip().strip('"') for s in names_line.split("{", 1)[1].split("}")[0].split(",")]
        exe = Path(tmp) / "bench"
        # every C source of the FMI 3.0 build (the FMI 2.0 adapter would clash with it)
        sources = sorted(str(c) for c in src.glob("*.c") if "fmi2" not in c.name)
        cmd = [
            "gcc",
            *[f for f in CFLAGS if f != "-fPIC"],
            *GENERATED_EXTRA,
            "-I",
            str(src),
            str(HARNESS),
            *sources,
            "-o",
            str(exe),
            "-lm",
        ]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"benchmark harness failed to compile:\n{proc.stderr}")
        for idx, m in enumerate(names):
            # explicit methods cost ~0.1 µs per step, the others (Newton, elliptic functions) µs
            n = n_explicit if m in ("rk4", "rk8", "splitting") else n_implicit
            n += n % 2  # the harness ping-pongs two steps per iteration
            res = subprocess.run([str(exe), str(n), str(idx)], check=True, capture_output=True, text=True)
            raw, fmi = (float(v) for v in res.stdout.split()[:2])
            out[m] = (raw, fmi)
    return out


# ----------------------------------------------------------------------------------
# co-simulation mode
# ----------------------------------------------------------------------------------
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


def fmu_cosim_once(drv: FmuDriver, method: str, h_max: float, dt: float, T: float) -> tuple[float, float, np.ndarray]:
    """(total s, controller s, final outputs) of one fmpy loop at Δ = dt with the PD controller."""
    ctrl = cosim_controller()
    drv.start(method, h_max, T)
    fmu = drv.inst.fmu
    get, setf, do = fmu.getFloat64, fmu.setFloat64, fmu.doStep
    vrs = drv.out_vrs[:7]
    names = drv.out_names[:7]
    in_names = [f"{b}[{k}]" for b in ("tau_body", "tau_world") for k in (1, 2, 3)]
    in_vrs = drv.inst._vrs(in_names)
    n = int(round(T / dt))
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


def fmu_compute_ctypes(drv: FmuDriver, method: str, h_max: float, dt: float, T: float) -> float:
    """Seconds spent in fmi3DoStep alone for the same number of Δ steps: the raw ctypes
    function of the FMU's library called in a loop (no fmpy wrapper, no get/set; the
    inputs stay at their start values, which does not change the substep count)."""
    import ctypes

    drv.start(method, h_max, T)
    fmu = drv.inst.fmu
    f = fmu.dll.fmi3DoStep
    f.argtypes = [
        ctypes.c_void_p,
        ctypes.c_double,
        ctypes.c_double,
        ctypes.c_bool,
        ctypes.POINTER(ctypes.c_bool),
        ctypes.POINTER(ctypes.c_bool),
        ctypes.POINTER(ctypes.c_bool),
        ctypes.POINTER(ctypes.c_double),
    ]
    f.restype = ctypes.c_int
    b1, b2, b3, last = ctypes.c_bool(), ctypes.c_bool(), ctypes.c_bool(), ctypes.c_double()
    p1, p2, p3, pl = ctypes.byref(b1), ctypes.byref(b2), ctypes.byref(b3), ctypes.byref(last)
    comp = fmu.component
    n = int(round(T / dt))
    tic = time.perf_counter()
    for k in range(n):
        if f(comp, k * dt, dt, False, p1, p2, p3, pl) != 0:
            raise RuntimeError(f"fmi3DoStep failed at t = {k * dt} s in the ctypes loop ({method}, h_max {h_max})")
    return time.perf_counter() - tic


def _exudyn_cosim(scene: Any, T: float, dt: float, solver: str, h: float, tol: float) -> tuple[Trajectory, float]:
    ctrl = cosim_controller()
    tr = run_exudyn(scene, dt, T, solver, h=h, tol=tol, input_fn=ctrl)
    return tr, ctrl.time_spent


@dataclass
class CosimResult:
    """Co-simulation section: reference, runs, and the target evaluation."""

    T: float
    dt: float
    ref: Reference
    runs: list[CosimRun]
    min_speedup: float | None
    min_pair: tuple[str, str] | None
    c_ns: dict[str, float]


FMU_COSIM = (("rk4", 1.0), ("rk4", 0.25), ("rk8", 1.0), ("gauss4", 1.0), ("splitting", 1.0), ("exact_free", 1.0))
EXUDYN_COSIM = (
    ("RK44", 1.0, 1e-10),
    ("RK67", 1.0, 1e-10),
    ("DOPRI5", 1.0, 1e-10),
    ("TrapezoidalIndex2", 1.0, 1e-10),
    ("GeneralizedAlpha", 1.0, 1e-10),
)


def cosim(fmu_path: Path, cfg: Config, c_ns: dict[str, float], progress: Progress | None) -> CosimResult:
    """Closed-loop co-simulation of the torque-driven body at Δ = cfg.cosim_dt: the FMU through
    fmpy and Exudyn chunk by chunk, both with the same Python controller, against a DOP853
    sampled-data reference; wall time split into controller, tool compute and fmpy overhead."""
    from modelsrc.scene import load_scene

    sc = load_scene(cfg.cosim_scene)
    T, dt = cfg.cosim_T, cfg.cosim_dt
    tr = closed_loop_scipy(sc, cosim_controller(), T, dt, rtol=REF_RTOL, atol=REF_ATOL)
    tr12 = closed_loop_scipy(sc, cosim_controller(), T, dt, rtol=CHECK_RTOL, atol=CHECK_ATOL)
    ref = Reference(
        tr.time,
        tr.w_body,
        tr.q,
        f"scipy DOP853 sampled-data loop, rtol {REF_RTOL:g}",
        0.0,
        float(np.max(np.abs(tr.w_body))),
        tr.wall_time,
    )
    ref.floor = errors(tr12.w_body, tr12.q, ref)[2]
    if progress:
        progress.advance("co-simulation: reference")
    runs: list[CosimRun] = []
    drv = FmuDriver(fmu_path, sc)
    try:
        for m, frac in FMU_COSIM:
            if m not in drv.method_values:
                continue
            h = dt * frac
            if progress:
                progress.show(f"co-simulation: FMU {m} h={h:g}")
            tot, ctl, out = fmu_cosim_once(drv, m, h, dt, T)
            reps = [(tot, ctl)] + [fmu_cosim_once(drv, m, h, dt, T)[:2] for _ in range(2)]
            tot = statistics.median(r[0] for r in reps)
            ctl = statistics.median(r[1] for r in reps)
            comp = statistics.median(fmu_compute_ctypes(drv, m, h, dt, T) for _ in range(3))
            e_w, e_R, e = errors(out[None, 4:7], out[None, :4], ref)
            n_sub = int(round(T / dt)) * max(1, math.ceil(1 / frac - 1e-9))
            est = c_ns.get(m, float("nan")) * 1e-9 * n_sub
            runs.append(
                CosimRun(
                    "FMU",
                    f"{m}, h_max = Δ/{1 / frac:g}" if frac != 1 else f"{m}, h_max = Δ",
                    tot,
                    ctl,
                    comp,
                    tot - ctl - comp,
                    e,
                    e_w,
                    e_R,
                    est,
                )
            )
            if progress:
                progress.advance(f"co-simulation: FMU {m}")
    finally:
        drv.close()
    for solver, frac, tol in EXUDYN_COSIM:
        if progress:
            progress.show(f"co-simulation: Exudyn {solver}")
        try:
            reps = [guarded(_exudyn_cosim, sc, T, dt, solver, dt * frac, tol, timeout=max(30.0, 200 * T))]
            if reps[0][0].wall_time < 0.5:
                reps += [
                    guarded(_exudyn_cosim, sc, T, dt, solver, dt * frac, tol, timeout=max(30.0, 200 * T))
                    for _ in range(2)
                ]
        except Exception as exc:  # noqa: BLE001
            runs.append(
                CosimRun(
                    "Exudyn",
                    f"{solver}: failed ({exc})",
                    float("nan"),
                    float("nan"),
                    float("nan"),
                    float("nan"),
                    float("nan"),
                    float("nan"),
                    float("nan"),
                )
            )
            continue
        trx = reps[0][0]
        tot = statistics.median(r[0].wall_time for r in reps)
        ctl = statistics.median(r[1] for r in reps)
        e_w, e_R, e = errors(trx.w_body, trx.q, ref)
        cfgs = f"{solver}, tol = {tol:g}, h ≤ Δ" if solver == "DOPRI5" else f"{solver}, h = Δ"
        runs.append(CosimRun("Exudyn", cfgs, tot, ctl, tot - ctl, 0.0, e, e_w, e_R))
        if progress:
            progress.advance(f"co-simulation: Exudyn {solver}")
    # target: for every Exudyn configuration, the fastest FMU run at least as accurate
    min_sp, pair = None, None
    fmu_runs = [r for r in runs if r.tool == "FMU"]
    for ex in (r for r in runs if r.tool == "Exudyn" and math.isfinite(r.total)):
        ok = [r for r in fmu_runs if r.err <= max(ex.err, 3 * ref.floor)]
        if not ok:
            continue
        best = min(ok, key=lambda r: r.total)
        sp = ex.total / best.total
        if min_sp is None or sp < min_sp:
            min_sp, pair = sp, (best.config, ex.config)
    return CosimResult(T, dt, ref, runs, min_sp, pair, c_ns)


# ----------------------------------------------------------------------------------
# long horizon
# ----------------------------------------------------------------------------------
@dataclass
class LongRun:
    """Long-horizon run of one FMU method: steps done, wall time, drifts, and why it
    stopped short of the planned count (if it did)."""

    method: str
    h: float
    steps: int
    planned: int
    wall: float
    drift_E: float
    drift_L: float
    drift_q: float
    times: np.ndarray
    dE_t: np.ndarray
    note: str = ""


def long_horizon(fmu_path: Path, cfg: Config, progress: Progress | None) -> list[LongRun]:
    """Each FMU method on free_asymmetric at its h_max for long_steps internal steps in
    long_chunks doSteps; a method whose first tenth projects beyond long_budget s (the
    Gauss methods: Newton iterations per step) stops there, at a tenth, and says so."""
    from modelsrc.scene import load_scene

    sc = load_scene(cfg.long_scene)
    h = float(sc.h_max)
    out: list[LongRun] = []
    drv = FmuDriver(fmu_path, sc)
    if not (drv.has_E and drv.has_L):
        drv.close()
        raise ValueError(f"long-horizon scene {sc.name} must be a free body with outputs E_kin and L_world")
    try:
        for m in sc.methods:
            planned = cfg.long_steps
            per_chunk = planned // cfg.long_chunks
            H = per_chunk * h
            if progress:
                progress.show(f"long horizon: {m}")
            drv.start(m, h, planned * h)
            do, get = drv.inst.fmu.doStep, drv.inst.fmu.getFloat64
            rows = [get(drv.out_vrs)]
            wall, steps, note = 0.0, 0, ""
            for k in range(cfg.long_chunks):
                tic = time.perf_counter()
                do(k * H, H)
                wall += time.perf_counter() - tic
                steps += per_chunk
                rows.append(get(drv.out_vrs))
                if k + 1 == max(1, cfg.long_chunks // 10) and wall * cfg.long_chunks / (k + 1) > cfg.long_budget:
                    note = (
                        f"stopped at {steps:.0e} steps: the full {planned:.0e} would take "
                        f"{wall * cfg.long_chunks / (k + 1):.2g} s > {cfg.long_budget:g} s budget"
                    )
                    break
            Y = np.array(rows)
            E = Y[:, 7]
            L = Y[:, 8:11]
            dE, dL, dq = drifts(sc, E, L, np.linalg.norm(Y[:, :4], axis=1))
            t = np.arange(len(rows)) * H
            out.append(LongRun(m, h, steps, planned, wall, dE, dL, dq, t, np.abs(E - E[0]) / E[0], note))
            if progress:
                progress.advance(f"long horizon: {m}")
    finally:
        drv.close()
    return out


# ----------------------------------------------------------------------------------
# plots and markdown
# ----------------------------------------------------------------------------------
STYLE = {"FMU": dict(ls="-", marker="o"), "Exudyn": dict(ls="--", marker="s"), "scipy": dict(ls=":", marker="^")}


def plot_scene(res: SceneResult, path: Path) -> None:
    """Work-precision diagram: headline error against wall time, log-log, one line per method."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    for ln in res.lines:
        if not ln.points:
            continue
        ax.loglog(
            [p.wall for p in ln.points],
            [max(p.err, ERR_FLOOR) for p in ln.points],
            ms=4,
            lw=1.2,
            label=ln.name,
            **STYLE[ln.family],
        )
    for lev in (LEVELS[0], LEVELS[-1]):
        ax.axhline(lev, color="0.7", lw=0.8)
    if res.ref.floor > 0:
        ax.axhline(3 * res.ref.floor, color="r", lw=0.8, ls=":", label="3 × reference error estimate")
    ax.set_xlabel("wall time of the integration (s), median of repeats")
    ax.set_ylabel("error at T: max(|Δω|∞/Ω, rotation angle)")
    ax.set_title(f"{res.name}: T = {res.T:g} s, batch mode (communication step T/{round(res.T / res.step)})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_cosim(res: CosimResult, path: Path) -> None:
    """Co-simulation: error against total wall time, and the time split per run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = [r for r in res.runs if math.isfinite(r.total)]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 5))
    for r in runs:
        a1.loglog(
            r.total,
            max(r.err, ERR_FLOOR),
            **{k: v for k, v in STYLE["FMU" if r.tool == "FMU" else "Exudyn"].items() if k == "marker"},
            ls="",
            label=f"{r.tool} {r.config}",
        )
    a1.set_xlabel("total wall time of the co-simulation loop (s)")
    a1.set_ylabel("error at T: max(|Δω|∞/Ω, rotation angle)")
    a1.grid(True, which="both", alpha=0.3)
    a1.legend(fontsize=7)
    labels = [f"{r.tool} {r.config.split(',')[0]}" + (" Δ/4" if "Δ/4" in r.config else "") for r in runs]
    y = np.arange(len(runs))
    comp = np.array([r.compute for r in runs])
    ctl = np.array([r.controller for r in runs])
    ovh = np.array([r.overhead for r in runs])
    a2.barh(y, comp, label="tool compute", color="C0")
    a2.barh(y, ovh, left=comp, label="fmpy overhead", color="C1")
    a2.barh(y, ctl, left=comp + ovh, label="Python controller", color="C2")
    a2.set_yticks(y, labels, fontsize=7)
    a2.set_xlabel("wall time (s), stacked (linear: segment lengths are the parts)")
    a2.legend(fontsize=7)
    fig.suptitle(f"co-simulation, Δ = {res.dt:g} s, T = {res.T:g} s ({round(res.T / res.dt)} steps)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_long(runs: Sequence[LongRun], path: Path) -> None:
    """Relative energy drift against time over the long horizon, one line per method."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5))
    for r in runs:
        ax.loglog(r.times[1:], np.maximum(r.dE_t[1:], ERR_FLOOR), label=f"{r.method} ({r.steps:.0e} steps)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("|E(t) − E(0)| / E(0)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _fmt(x: float | None, spec: str = ".2g") -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    return format(x, spec)


def _best_txt(b: Best) -> str:
    if b.time is None:
        return "n/a"
    if b.lower_bound:
        return f"> {b.time:.2g} s (not reached)"
    return f"{b.line.split(' ', 1)[1]} {'≤ ' if b.upper_bound else ''}{b.time:.2g} s"


def _speedup_txt(fmu: Best, other: Best) -> str:
    """FMU speed-up over a baseline: '≥' when it is a lower bound (the baseline did not
    reach the level, or the FMU time is its cheapest rung's), n/a when undefined."""
    if fmu.time is None or fmu.lower_bound or other.time is None:
        return "n/a"
    if other.upper_bound and not other.lower_bound:
        if fmu.upper_bound:
            return "n/a"  # both are upper bounds: no order
        return f"≤ {other.time / fmu.time:.0f}×"
    bound = other.lower_bound or fmu.upper_bound
    return ("≥ " if bound else "") + f"{other.time / fmu.time:.0f}×"


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
                fails.append(f"{res.name} {row.level:.0e}: no FMU method reached the level")
                continue
            for fam, other in (("Exudyn", row.exudyn), ("scipy", row.scipy)):
                if other.time is None:
                    continue
                sp = other.time / row.fmu.time
                if sp < TARGET_BATCH_SPEEDUP:
                    fails.append(
                        f"{res.name} {row.level:.0e}: {sp:.1f}× over {fam}"
                        + (" (lower bound)" if other.lower_bound or row.fmu.upper_bound else "")
                    )
                elif other.upper_bound and not other.lower_bound:
                    # the baseline's cheapest rung met the level: it might be faster still
                    unverified.append(f"{res.name} {row.level:.0e}: {sp:.0f}× over {fam}")
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
                    out[fam] = (sp, f"{res.name} at {row.level:.0e}")
    return out


def write_markdown(
    path: Path,
    cfg: Config,
    results: Sequence[SceneResult],
    bench: dict[str, dict[str, tuple[float, float]]],
    cos: CosimResult | None,
    longs: Sequence[LongRun],
    timings: dict[str, float],
) -> None:
    """Write report.md (targets first, then per-scene diagrams and tables)."""
    L: list[str] = []
    w = L.append
    w("# Work-precision report: integrators inside the FMU against Exudyn and scipy\n")
    w(
        f'Generated by `python -c "from rbcheck.report import main; main()"` (`rbfmu report`) in '
        f"{timings.get('total', float('nan')):.0f} s on {_cpu()} (load average at start "
        f"{timings.get('load0', float('nan')):.2f}, other jobs were sharing the CPU). Every number below comes "
        "from this one run; wall times are medians of repeats taken in it. Compare them as ratios.\n"
    )
    # ---- targets
    w("## Targets\n")
    w("| target | status | numbers |\n|---|---|---|")
    worst = None
    for sc, per in bench.items():
        for m, (raw, fmi) in per.items():
            r = fmi / raw
            if worst is None or r > worst[0]:
                worst = (r, sc, m, raw, fmi)
    if worst:
        w(
            f"| internal step ≤ {TARGET_STEP_RATIO}× the raw generated step in a C loop | "
            f"{'met' if worst[0] <= TARGET_STEP_RATIO else 'NOT met'} | worst ratio {worst[0]:.3f} "
            f"({worst[1]}, {worst[2]}: {worst[4]:.1f} vs {worst[3]:.1f} ns); all methods: table below |"
        )
    if results:
        ok, fails, unver = batch_target(results)
        mins = min_batch_speedups(results)
        mtxt = "; ".join(f"smallest over {f}: {v[0]:.1f}× ({v[1]})" for f, v in mins.items())
        status = "met" if ok else ("NOT met" if fails else "met where verifiable")
        w(
            f"| batch: best FMU method ≥ {TARGET_BATCH_SPEEDUP:.0f}× faster than best Exudyn and best scipy at every "
            f"resolved level 1e-4…1e-11, every scene | {status} | {mtxt}"
            + (
                f"; {len(fails)} failing cells: " + "; ".join(fails[:8]) + (" …" if len(fails) > 8 else "")
                if fails
                else ""
            )
            + (
                f"; {len(unver)} cells where the speed-up is ≥ 10× but only an upper bound (the baseline's loosest "
                "rung already met the level, a looser one might be faster): " + "; ".join(unver)
                if unver
                else ""
            )
            + " |"
        )
    if cos is not None:
        sp = cos.min_speedup
        w(
            f"| co-simulation at Δ = {cos.dt:g} s: ≥ {TARGET_COSIM_SPEEDUP:.0f}× faster than Exudyn chunk by chunk | "
            f"{'met' if sp is not None and sp >= TARGET_COSIM_SPEEDUP else 'NOT met'} | smallest speed-up "
            f"{_fmt(sp, '.1f')}× (FMU {cos.min_pair[0] if cos.min_pair else '-'} vs Exudyn "
            f"{cos.min_pair[1] if cos.min_pair else '-'}), total loop time incl. the Python controller both sides |"
        )
    w(
        f"| whole report < 10 min on 2 cores | {'met' if timings.get('total', 1e9) < 600 else 'NOT met'} | "
        f"{timings.get('total', float('nan')):.0f} s total; parts: "
        + ", ".join(f"{k} {v:.0f} s" for k, v in timings.items() if k not in ("total", "load0"))
        + " |\n"
    )
    # ---- definitions
    w("## What is measured\n")
    w(
        "- **Error** at the end time T of each run against the scene's reference: "
        "e_ω = ‖ω(T) − ω_ref(T)‖∞ (rad/s, body frame, max-norm over the three components) and "
        "e_R = rotation angle of R(T)ᵀ R_ref(T) (rad). The diagrams and tables use the dimensionless "
        "**e = max(e_ω/Ω, e_R)**, Ω = max ‖ω_ref‖∞ over the communication points (rad/s)."
    )
    w(
        "- **Invariant drift**, maximum over the communication points: relative E (E_kin of a free body, "
        "E_total of the heavy top), relative |L_world| (free body) or L_world·e_z relative to |L| (heavy top: p_φ, "
        "docs/theory.md §4.2), and ||q| − 1| (FMU and scipy; Exudyn's Lie-group node has no quaternion). "
        "n/a where friction or torques act."
    )
    w(
        "- **Wall time** of the integration loop only (FMU: the fmpy doStep loop, instance already loaded and reset "
        "with fmi3Reset, inputs set with one setFloat64 when a table switches; Exudyn: `simulate_scene`'s timed solve, model assembly excluded; scipy: the `solve_ivp` "
        "calls), median of 5 repeats below 20 ms, 3 below 0.2 s, else one run."
    )
    w(
        f"- **Batch mode**: communication step T/{cfg.comm_fraction} (plus input-table switching times), so the "
        "internal steps do the work; every tool restarts at the same points. FMU: `h_max` ladder in θ = h_max·Ω "
        "(explicit methods may take more substeps by their stiffness bound). Exudyn: RK44/RK67 and the implicit "
        'solvers on a step ladder (gravity scenes: explicit solvers on the "pivot" model, implicit ones on the '
        '"joint" model with a spherical joint), DOPRI5 on a tolerance ladder (rtol = atol = tol, max step = the '
        f"communication step). scipy `solve_ivp` (DOP853, Radau, LSODA) on the numpy equations of "
        f"`rbcheck.baselines` (scalar code, no Jacobian given), rtol ladder with atol = {cfg.atol_factor:g}·rtol set "
        "explicitly on every state."
    )
    w(
        f"- Ladders stop when the next rung is predicted to take more than {cfg.cap_fmu:g} s (FMU), "
        f"{cfg.cap_exudyn:g} s (Exudyn), {cfg.cap_scipy:g} s (scipy), when e < {cfg.floor:g}, or when e stops "
        "decreasing (round-off or reference floor). A baseline that did not reach a level is given as a lower "
        "bound (its most expensive run), and the speed-up as '≥'."
    )
    w(
        "- **Fastest method per level**: each line's wall time at the level is interpolated linearly in "
        "log–log between the two rungs around the crossing; a line whose cheapest rung already meets the level "
        "counts with that rung's time (an upper bound for that line).\n"
    )
    # ---- per scene
    for res in results:
        w(f"## {res.name}\n")
        w(
            f"T = {res.T:g} s, {res.n_comm} communication steps. Reference: {res.ref.source} "
            f"(its own error estimated at e ≈ {res.ref.floor:.1e}; levels below 3× that are marked unresolved). "
            f"Ω = {res.ref.omega_scale:.4g} rad/s.\n"
        )
        w(f"![{res.name}]({res.name}.png)\n")
        w("| error level | fastest | best FMU | best Exudyn | best scipy | FMU speed-up vs Exudyn | vs scipy |")
        w("|---|---|---|---|---|---|---|")
        for row in res.table:
            flag = "" if row.resolved else " (unresolved)"
            w(
                f"| {row.level:.0e}{flag} | {row.fastest or 'n/a'} | {_best_txt(row.fmu)} | {_best_txt(row.exudyn)} | "
                f"{_best_txt(row.scipy)} | {_speedup_txt(row.fmu, row.exudyn)} | {_speedup_txt(row.fmu, row.scipy)} |"
            )
        w("")
        w("<details><summary>all runs</summary>\n")
        w(
            "| line | parameter | steps / RHS calls | wall (s) | e_ω (rad/s) | e_R (rad) | e | E drift | L drift | "
            "max ‖q|−1| |"
        )
        w("|---|---|---|---|---|---|---|---|---|---|")
        for ln in res.lines:
            for p in ln.points:
                w(
                    f"| {ln.name} | {p.param} | {p.work} | {p.wall:.3g} | {p.e_w:.2e} | {p.e_R:.2e} | {p.err:.2e} | "
                    f"{_fmt(p.drift_E, '.1e')} | {_fmt(p.drift_L, '.1e')} | {_fmt(p.drift_q, '.1e')} |"
                )
        w("\n</details>\n")
        orders = []
        for ln in res.lines:
            if ln.family == "FMU":
                p = asymptotic_order(ln.points, low=max(1e3 * res.ref.floor, 1e-11))
                if p is not None:
                    orders.append(f"{ln.name.split()[1]} {p:.2f}")
        if orders:
            w(
                "Observed orders of the FMU methods (median local slope of log e against log h_max between rungs "
                f"with 1e-2 ≥ e ≥ {max(1e3 * res.ref.floor, 1e-11):.0e} and a wall time that grew ≥ 1.5×: the coarsest "
                "explicit rungs may take more substeps than h_max asks, by the stiffness bound, and a Gauss method after a "
                "failed Newton check): " + ", ".join(orders) + ".\n"
            )
        notes = [f"{ln.name}: {n}" for ln in res.lines for n in ln.notes]
        if notes:
            w("Ladder notes: " + "; ".join(notes) + ".\n")
    # ---- co-simulation
    if cos is not None:
        w("## Co-simulation mode\n")
        w(
            f"`{cfg.cosim_scene}` driven by a Python quaternion-feedback PD attitude controller "
            "(`rbcheck.baselines.AttitudePD`: slew from rest to a 2 rad rotation about (1,2,2)/3, kp = 1 N·m, "
            "kd = 2 N·m·s/rad, plus a 0.02 N·m world-frame disturbance on tau_world) sampled every "
            f"Δ = {cos.dt:g} s for T = {cos.T:g} s ({round(cos.T / cos.dt)} steps). FMU: fmpy doStep + setFloat64 of "
            "the 6 torques + getFloat64 of the 7 states per step. Exudyn: `simulate_scene(input_fn=...)`, one "
            f"`SolveSteps` per Δ. Reference: {cos.ref.source} ("
            + (
                f"own error estimate {cos.ref.floor:.1e}"
                if cos.ref.floor > 0
                else f"bit-identical to the same loop at rtol {CHECK_RTOL:g}: at |ω|Δ < 1e-3 the step error is below "
                "round-off at both tolerances"
            )
            + "). "
            "FMU compute = the raw `fmi3DoStep` of the FMU's library called in a ctypes loop (includes the ctypes "
            "call, ~1 µs); fmpy overhead = total − controller − compute; C estimate = the harness's ns per internal "
            "step × substeps.\n"
        )
        w("![co-simulation](cosim.png)\n")
        w(
            "| tool | configuration | total (s) | controller (s) | compute (s) | fmpy overhead (s) | C estimate (s) | "
            "µs per Δ | e | e_ω (rad/s) | e_R (rad) |"
        )
        w("|---|---|---|---|---|---|---|---|---|---|---|")
        n = round(cos.T / cos.dt)
        for r in cos.runs:
            w(
                f"| {r.tool} | {r.config} | {_fmt(r.total, '.3g')} | {_fmt(r.controller, '.3g')} | {_fmt(r.compute, '.3g')} | "
                f"{_fmt(r.overhead, '.3g') if r.tool == 'FMU' else '—'} | {_fmt(r.compute_c_estimate, '.2g')} | "
                f"{_fmt(r.total / n * 1e6, '.1f')} | {_fmt(r.err, '.1e')} | {_fmt(r.e_w, '.1e')} | {_fmt(r.e_R, '.1e')} |"
            )
        fm = [r for r in cos.runs if r.tool == "FMU"]
        ex = [r for r in cos.runs if r.tool == "Exudyn" and math.isfinite(r.total)]
        if fm and ex:
            bf = min(fm, key=lambda r: r.total)
            be = min(ex, key=lambda r: r.total)
            w("")
            w(
                f"Fastest FMU loop {bf.total:.3g} s ({bf.config}, e = {bf.err:.1e}) against the fastest Exudyn loop "
                f"{be.total:.3g} s ({be.config}, e = {be.err:.1e}): {be.total / bf.total:.1f}× overall; without the "
                f"controller's own time (identical code on both sides) {(be.total - be.controller) / (bf.total - bf.controller):.1f}×; "
                f"FMU compute alone against Exudyn without controller {(be.total - be.controller) / bf.compute:.0f}×. "
                f"The FMU loop is {100 * (bf.overhead + bf.controller) / bf.total:.0f} % Python (fmpy calls and "
                f"controller) and {100 * bf.compute / bf.total:.0f} % fmi3DoStep.\n"
            )
    # ---- long horizon
    if longs:
        w("## Long horizon\n")
        w(
            f"`{cfg.long_scene}` (tennis-racket flips every few seconds) at h_max = {longs[0].h:g} s, "
            f"{cfg.long_chunks} doSteps; drift = maximum over the {cfg.long_chunks + 1} doStep boundaries.\n"
        )
        w("![long horizon](long_horizon.png)\n")
        w(
            "ns per step here is the wall time of the doStep loop over the steps, under whatever load the machine had "
            "at that moment; the C table below has the best-of-5 cost per step.\n"
        )
        w(
            "| method | internal steps | simulated time (s) | wall (s) | ns per step | E drift | |L| drift | max ‖q|−1| | note |"
        )
        w("|---|---|---|---|---|---|---|---|---|")
        for r in longs:
            w(
                f"| {r.method} | {r.steps:.2e} | {r.steps * r.h:.4g} | {r.wall:.3g} | {1e9 * r.wall / r.steps:.0f} | "
                f"{r.drift_E:.1e} | {r.drift_L:.1e} | {r.drift_q:.1e} | {r.note or ('as planned' if r.steps == r.planned else '')} |"
            )
        short = [r.method for r in longs if r.steps < r.planned]
        if short:
            w(
                f"\n{cfg.long_steps:.0e} steps were planned for every method; {', '.join(short)} stopped after the "
                f"first tenth because the measured cost projected the full run beyond the {cfg.long_budget:g} s budget "
                "per method (Newton iterations make an implicit step 5–100× dearer than an explicit one; C step cost "
                "below). Their drift is over the shorter horizon.\n"
            )
    # ---- C step cost
    if bench:
        w("## Internal step cost in C\n")
        w(
            "The harness `fmu/c/bench_step.c` compiled against each FMU's sources: the raw generated step function in "
            "a C loop, and the same steps through one long `fmi3DoStep` (best of 5).\n"
        )
        w("| scene | method | raw step (ns) | through fmi3DoStep (ns) | ratio | ≤ 1.2 |")
        w("|---|---|---|---|---|---|")
        for sc, per in bench.items():
            for m, (raw, fmi) in per.items():
                w(
                    f"| {sc} | {m} | {raw:.1f} | {fmi:.1f} | {fmi / raw:.3f} | {'yes' if fmi / raw <= TARGET_STEP_RATIO else 'NO'} |"
                )
        w("")
    path.write_text("\n".join(L) + "\n")


def _cpu() -> str:
    try:
        for ln in Path("/proc/cpuinfo").read_text().splitlines():
            if ln.startswith("model name"):
                return f"{ln.split(':', 1)[1].strip()} ({os.cpu_count()} CPUs)"
    except OSError:
        pass
    return f"{os.cpu_count()} CPUs"


# ----------------------------------------------------------------------------------
# entry point
# ----------------------------------------------------------------------------------
def _parse(argv: Sequence[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="rbfmu report", description="Work-precision report (docs/report/).")
    p.add_argument("--out", default=str(DEFAULT_OUT), help="output folder (default docs/report)")
    p.add_argument(
        "--scenes", nargs="+", default=None, help=f"scenes of the batch part (default {' '.join(DEFAULT_SCENES)})"
    )
    p.add_argument("--quick", action="store_true", help="tiny ladders (smoke test), not a real report")
    p.add_argument(
        "--skip", nargs="*", default=[], choices=["batch", "cosim", "long", "bench"], help="parts to leave out"
    )
    return p.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    """Regenerate the report; returns 0 on success, 2 on bad arguments (message on stderr)."""
    t_start = time.perf_counter()
    try:
        args = _parse(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    from modelsrc.errors import ModelInputError
    from modelsrc.scene import list_scenes

    scenes = tuple(args.scenes) if args.scenes else DEFAULT_SCENES
    known = list_scenes()
    bad = [s for s in scenes if s not in known]
    if bad:
        print(f"rbfmu report: unknown scene {bad[0]!r}; known scenes: {', '.join(known)}", file=sys.stderr)
        return 2
    cfg = Config.quick(scenes) if args.quick else replace(Config(), scenes=scenes)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    timings: dict[str, float] = {"load0": os.getloadavg()[0]}
    from fmu.build_fmu import build_fmu
    from modelsrc.scene import load_scene

    import rbcheck.exudyn_models  # noqa: F401 - load Exudyn once, before the forked children

    need = set(cfg.scenes if "batch" not in args.skip else ())
    if "cosim" not in args.skip:
        need.add(cfg.cosim_scene)
    if "long" not in args.skip:
        need.add(cfg.long_scene)
    if "bench" not in args.skip:
        need.update(cfg.bench_scenes)
    methods = {s: load_scene(s).methods for s in need}
    n_units = (
        len(need)
        + (count_batch_units(cfg, methods) if "batch" not in args.skip else 0)
        + (
            1 + len([m for m, _ in FMU_COSIM if m in methods[cfg.cosim_scene]]) + len(EXUDYN_COSIM)
            if "cosim" not in args.skip
            else 0
        )
        + (len(methods[cfg.long_scene]) if "long" not in args.skip else 0)
        + (len(cfg.bench_scenes) if "bench" not in args.skip else 0)
    )
    progress = Progress(n_units)
    with tempfile.TemporaryDirectory(prefix="rbfmu_report_") as tmp:
        try:
            tic = time.perf_counter()
            fmus = {}
            for name in sorted(need):
                progress.show(f"building {name}")
                fmus[name] = build_fmu(load_scene(name), Path(tmp))
                progress.advance(f"built {name}")
            timings["build"] = time.perf_counter() - tic
            bench: dict[str, dict[str, tuple[float, float]]] = {}
            if "bench" not in args.skip:
                tic = time.perf_counter()
                for name in cfg.bench_scenes:
                    progress.show(f"C step cost {name}")
                    bench[name] = c_step_ns_all(fmus[name], cfg.bench_n_explicit, cfg.bench_n_implicit)
                    progress.advance(f"C step cost {name}")
                timings["C bench"] = time.perf_counter() - tic
            results: list[SceneResult] = []
            if "batch" not in args.skip:
                tic = time.perf_counter()
                for name in cfg.scenes:
                    res = batch_scene(name, fmus[name], cfg, progress)
                    plot_scene(res, out / f"{name}.png")
                    results.append(res)
                    timings[f"batch {name}"] = (
                        time.perf_counter() - tic - sum(v for k, v in timings.items() if k.startswith("batch "))
                    )
            cos = None
            if "cosim" not in args.skip:
                tic = time.perf_counter()
                c_ns = {}
                if cfg.cosim_scene in bench:
                    c_ns = {m: v[1] for m, v in bench[cfg.cosim_scene].items()}
                else:
                    c_ns = {
                        m: v[1]
                        for m, v in c_step_ns_all(
                            fmus[cfg.cosim_scene], cfg.bench_n_explicit, cfg.bench_n_implicit
                        ).items()
                    }
                cos = cosim(fmus[cfg.cosim_scene], cfg, c_ns, progress)
                plot_cosim(cos, out / "cosim.png")
                timings["co-simulation"] = time.perf_counter() - tic
            longs: list[LongRun] = []
            if "long" not in args.skip:
                tic = time.perf_counter()
                longs = long_horizon(fmus[cfg.long_scene], cfg, progress)
                plot_long(longs, out / "long_horizon.png")
                timings["long horizon"] = time.perf_counter() - tic
        except ModelInputError as exc:
            progress.finish()
            print(f"rbfmu report: {exc}", file=sys.stderr)
            return 2
    progress.finish()
    timings["total"] = time.perf_counter() - t_start
    write_markdown(out / "report.md", cfg, results, bench, cos, longs, timings)
    print(
        f"report written to {out / 'report.md'} in {timings['total']:.0f} s "
        f"(parts: {', '.join(f'{k} {v:.0f} s' for k, v in timings.items() if k not in ('total', 'load0'))})"
    )
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
