"""Error-control part of the report: achieved error against requested tolerance, and its cost against fixed steps.

For every scene and every method with an embedded error estimate
(`modelsrc.methods.error_controlled`) the FMU runs in batch mode (communication step
`batch.batch_step`, inputs held at their mean over each step, the reference of
`references.make_reference`) once per tolerance of `Config.tolerances` (h_max = 0, no
cap) and once per rung of the batch part's fixed-step ladder (tolerance = 0, h_max =
θ/Ω). `tolerance` is a relative error per second (docs/theory.md §5.5, the comment at
`modelsrc.methods.DEFAULT_TOLERANCE`): after T seconds the error should be about
tolerance·T, so the measure here is the ratio e / (tolerance·T) of the headline error e
(rbcheck.workprecision docstring). The cost of error control is the wall time and the
internal steps (accepted + rejected) of a controlled run against those of the fixed-step
ladder interpolated in log–log at the same error (`measures.time_at_level`). Its wall
times are re-taken in rounds that alternate every run of both ladders (`retime`): a run
of a few milliseconds timed alone lands in whatever second the machine is slow, and on a
shared 2-core VM whose speed varies by ±50 % from second to second, that put ±0.3–0.5 of
noise on the ratio; the fastest of several rounds, taken minutes apart for no run, is the
cost without the machine's interruptions (the timeit convention), the same for both.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from modelsrc.methods import error_controlled
from modelsrc.scene import Scene, list_scenes, load_scene

from ..baselines.rigid_body import comm_grid
from .batch import batch_step, predicted_wall, run_ladder, step_rungs
from .config import Config
from .harness import FmuDriver, advance, show
from .measurable import measurable_scenes
from .measures import Line, Point, time_at_level
from .references import Reference, make_reference

if TYPE_CHECKING:
    from tqdm import tqdm

# Interleaved re-timing of a method's two ladders (`retime`): at most this many rounds,
# and a run takes part in a round only while its timings so far add up to less than
# RETIME_BUDGET s, so that the few expensive rungs (up to cfg.tol_cap each) are timed
# fewer times and the re-timing costs at most about a second per run.
RETIME_ROUNDS = 7
RETIME_BUDGET = 0.25

# A controlled run counts towards the band of e/(tolerance·T) only where the reference can
# tell its error apart: tolerance·T at least this many times the reference's own error
# estimate (the batch part marks levels below 3x it unresolved, docs/report/report.md).
RESOLVED_FACTOR = 3.0
EPS = 2.220446049250313e-16


@dataclass
class ControlPoint(Point):
    """A run of the FMU with its step report summed over the doSteps: accepted and rejected
    internal steps (`internal_steps`, `rejected_steps`; `work` is their sum), the tolerance
    (relative error per second, 0 for fixed steps) and h_max (s, 0: no cap)."""

    accepted: int = 0
    rejected: int = 0
    tolerance: float = 0.0
    h_max: float = 0.0


class ControlDriver(FmuDriver):
    """The report's FMU driver (harness.FmuDriver) that also reads the step report after
    every doStep of a recording run, and starts with a chosen tolerance (1/s) and start
    values (`start_values`: variable name -> value, e.g. a faster spin w_body[k] in rad/s)."""

    def __init__(self, fmu_path: Path, scene: Scene):
        super().__init__(fmu_path, scene)
        self.n_plain = len(self.out_names)
        self.out_names += ["internal_steps", "rejected_steps"]
        self.out_vrs = self.inst.value_references(self.out_names)
        self.tolerance = 0.0
        self.start_values: dict[str, float] = {}
        self.defaults = False

    def start(self, method: str, h_max: float, stop_time: float) -> None:
        """Reset, set the start values, the method, `self.tolerance` and h_max (s) (or leave
        every setting at the FMU's defaults when `self.defaults`), initialise on [0, stop_time]."""
        if method not in self.method_values:
            raise ValueError(f"method {method!r} is not in this FMU; it has {sorted(self.method_values)}")
        self.inst.reset()
        values: dict[str, float] = dict(self.start_values)
        if not self.defaults:
            values.update(method=self.method_values[method], tolerance=self.tolerance, h_max=float(h_max))
        self.inst.set(values)
        self.inst.initialize(0.0, stop_time)

    def measure(self, method: str, h_max: float, grid: np.ndarray, ref: Reference, max_repeats: int) -> ControlPoint:
        """Error, drifts and step report of a recording run, median wall time (s) of runs
        that read nothing (harness.FmuDriver.point, with the steps actually taken)."""
        _, Y = self.run(method, h_max, grid, record=True)
        e_w, e_R, e, dE, dL, dq = self.accuracy(Y, ref)
        acc, rej = (round(float(np.sum(Y[1:, self.n_plain + j]))) for j in (0, 1))
        wall = self.median_wall(method, h_max, grid, max_repeats)
        tol = self.tolerance
        label = f"tol={tol:.0e}" if tol > 0 else f"h={h_max:.3g}"
        return ControlPoint(
            label, tol if tol > 0 else h_max, wall, e, e_w, e_R, dE, dL, dq, acc + rej, acc, rej, tol, h_max
        )


@dataclass
class MethodControl:
    """One method on one scene: the tolerance ladder (`controlled`, loosest first) and the
    fixed-step ladder (`fixed`, coarsest first), with the ladders' notes."""

    method: str
    controlled: Line
    fixed: Line

    def ratios(self, T: float, floor: float) -> list[tuple[float, float, bool]]:
        """(tolerance, e/(tolerance·T), resolved) per controlled run; resolved when
        tolerance·T ≥ RESOLVED_FACTOR × the reference's error estimate `floor`."""
        return [
            (p.value, p.err / (p.value * T), p.value * T >= RESOLVED_FACTOR * floor) for p in self.controlled.points
        ]

    def cost_ratios(self) -> list[tuple[float, float | None, float | None, bool]]:
        """Per controlled run: (its error, wall ratio, work ratio, bound) against the fixed
        ladder at the same error (log–log interpolation, measures.time_at_level); None where
        the fixed ladder never reached that error. bound: the coarsest fixed rung already
        met it with more than one step per communication interval (a coarser rung might have
        been cheaper), so the fixed cost used is an upper bound (the ratio a lower bound)."""
        wall = [(p.wall, p.err) for p in self.fixed.points]
        work = [(float(p.work), p.err) for p in self.fixed.points]
        out: list[tuple[float, float | None, float | None, bool]] = []
        for p in self.controlled.points:
            level = max(p.err, 1e-300)
            tw, tk = time_at_level(wall, level), time_at_level(work, level)
            out.append(
                (
                    p.err,
                    p.wall / tw[0] if tw else None,
                    p.work / tk[0] if tk else None,
                    bool(tw and tw[1] and self.fixed.points[0].work > (self.fixed.min_work or 0)),
                )
            )
        return out


@dataclass
class SceneControl:
    """Everything the error-control part measured on one scene: stop time T (s, possibly
    shorter than the scene's, `shortened`), communication step (s), the reference, and
    the ladders per method."""

    name: str
    T: float
    step: float
    n_comm: int
    shortened: bool
    ref: Reference
    methods: list[MethodControl] = field(default_factory=list)

    def band(self) -> tuple[float, float] | None:
        """(min, max) of e/(tolerance·T) over the resolved controlled runs of every method."""
        r = [x for m in self.methods for _, x, ok in m.ratios(self.T, self.ref.floor) if ok]
        return (min(r), max(r)) if r else None


def retime(drv: ControlDriver, method: str, lines: Sequence[Line], grid: np.ndarray) -> None:
    """Set every point's wall (s) of `lines` (one method's ladders: controlled points carry
    their tolerance, fixed ones their h_max) to the fastest of RETIME_ROUNDS rounds that each
    time every run once, in ladder order, the first measurement (`measure`) included."""
    spent = {id(p): 0.0 for ln in lines for p in ln.points}
    for _ in range(RETIME_ROUNDS):
        for ln in lines:
            for p in ln.points:
                if spent[id(p)] >= RETIME_BUDGET:
                    continue
                assert isinstance(p, ControlPoint)
                drv.tolerance = p.tolerance
                wall = drv.run(method, p.h_max, grid, record=False)[0]
                spent[id(p)] += wall
                p.wall = min(p.wall, wall)


def tolerance_ladder(
    line: Line, tolerances: Sequence[float], run_one: Callable[[float], Point], cap: float, progress: tqdm[Any] | None
) -> Line:
    """Run the tolerances loosest first, every one (unlike batch.run_ladder, a rung equal to
    the previous one stays: the table has a row per tolerance), until the next is predicted
    to take more than `cap` s (the last wall time × the growth of the last two, at least
    2×) or two rungs failed (the FMU refusing a step it cannot make, a work limit)."""
    failures = 0
    for tol in tolerances:
        pts = line.points
        predicted = predicted_wall(pts, 2.0, 2.0)
        if predicted > cap:
            line.notes.append(f"stopped before {tol:.0e}: predicted {predicted:.2g} s > cap {cap:g} s")
            break
        show(progress, f"{line.name} {tol:.0e}")
        try:
            p = run_one(tol)
        except Exception as exc:  # the FMU's refusal is a result, noted in the report
            failures += 1
            line.notes.append(f"{tol:.0e}: failed ({str(exc).splitlines()[0][:160]})")
            if failures >= 2:
                break
            continue
        pts.append(p)
    return line


def tolerance_scenes(cfg: Config) -> tuple[str, ...]:
    """The scenes of the part: cfg.tol_scenes (possibly none), or when it is None every
    shipped scene the part can measure (`measurable_scenes`)."""
    if cfg.tol_scenes is not None:
        return cfg.tol_scenes
    return measurable_scenes(list_scenes())


def controlled_methods(scene: Scene) -> list[str]:
    """The scene's methods that choose their steps from an error estimate."""
    return [m for m in scene.methods if error_controlled(m)]


def tolerance_scene(
    name: str, fmu_path: Path, cfg: Config, progress: tqdm[Any] | None, methods: Sequence[str] | None = None
) -> SceneControl:
    """The tolerance ladder (cfg.tolerances, loosest first, each run predicted above
    cfg.tol_cap s stops it) and the fixed-step ladder (cfg.fmu_theta, same cap) of every
    error-controlled method of scene `name` in batch mode, over its stop time or
    cfg.tol_stop_time[name] (s) where that is shorter. methods: a subset (default: all)."""
    sc = load_scene(name)
    allowed = controlled_methods(sc)
    bad = [m for m in methods or () if m not in allowed]
    if bad:
        raise ValueError(f"method {bad[0]!r} has no error control in scene {name}; allowed: {', '.join(allowed)}")
    T = min(float(sc.stop_time), cfg.tol_stop_time.get(name, math.inf))
    H = min(batch_step(sc, cfg), T / cfg.comm_fraction)
    grid = comm_grid(sc, T, H)
    show(progress, f"tolerance {name}: reference")
    ref = make_reference(sc, grid)
    res = SceneControl(sc.name, T, H, len(grid) - 1, float(sc.stop_time) > T, ref)  # the name, not a file's path
    drv = ControlDriver(fmu_path, sc)
    try:
        for m in methods if methods is not None else allowed:
            ctl, fix = Line(f"FMU {m} tolerance", "FMU"), Line(f"FMU {m} fixed", "FMU", min_work=len(grid) - 1)

            def controlled(tol: float, m: str = m) -> Point:
                drv.tolerance = tol
                return drv.measure(m, 0.0, grid, ref, cfg.max_repeats)

            def fixed(h: float, m: str = m) -> Point:
                drv.tolerance = 0.0
                return drv.measure(m, h, grid, ref, cfg.max_repeats)

            tolerance_ladder(ctl, cfg.tolerances, controlled, cfg.tol_cap, progress)
            thetas = cfg.fmu_theta.get(m, cfg.fmu_theta_default) or ()
            run_ladder(fix, step_rungs(thetas, ref.omega_scale, grid), fixed, cfg.tol_cap, cfg.floor, 2.0, progress)
            show(progress, f"{name} {m}: timing both ladders in rounds")
            retime(drv, m, (ctl, fix), grid)
            res.methods.append(MethodControl(m, ctl, fix))
            advance(progress, f"tolerance {name}: {m}")
    finally:
        drv.close()
    return res


def count_tolerance_units(cfg: Config, methods: dict[str, Sequence[str]]) -> int:
    """Progress units of the error-control part: one per scene and controlled method, one
    per fast-spin case and one per scene at its defaults (methods: scene -> its methods)."""
    scenes = tolerance_scenes(cfg)
    per_scene = sum(len([m for m in methods[s] if error_controlled(m)]) for s in scenes)
    return per_scene + len(cfg.spin_rates) * len(cfg.spin_bodies) + len(scenes)
