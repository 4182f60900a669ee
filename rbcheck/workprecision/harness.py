"""Timing harness of the report: median wall times, a guarded child process, and the FMU driver stepped through fmpy.

The driver uses only FmuInstance's public methods (fmu/drive/instance.py): the instance is loaded
once per scene and reset (fmi3Reset) between runs, so the timed loop is the doStep loop
alone.
"""

from __future__ import annotations

import itertools
import multiprocessing
import statistics
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fmu.drive.instance import FmuInstance
from modelsrc.scene import Scene

from .measures import Point, nominal_steps
from .references import Reference, conserved_quantities, drifts, errors

if TYPE_CHECKING:
    from tqdm import tqdm


def median_time(fn: Callable[[], float], first: float, max_repeats: int) -> float:
    """Median of `first` (a timing already taken) and further timings by fn(), repeated
    more often the cheaper a run is: 5 below 20 ms, 3 below 0.2 s, else just `first`."""
    n = 1 if first >= 0.2 else (3 if first >= 0.02 else 5)
    times = [first] + [fn() for _ in range(min(n, max_repeats) - 1)]
    return float(statistics.median(times))


def _guard_child(conn, fn, args, kwargs):  # pragma: no cover - runs in the forked child
    try:
        conn.send(("ok", fn(*args, **kwargs)))
    except BaseException as exc:  # report anything to the parent
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


def _timed(fn: Callable[..., Any], name: str, fmu_path: Path, cfg: Any) -> tuple[Any, float]:
    tic = time.perf_counter()
    result = fn(name, fmu_path, cfg, None)
    return result, time.perf_counter() - tic


def map_scenes(
    fn: Callable[..., Any],
    names: Sequence[str],
    fmus: dict[str, Path],
    cfg: Any,
    bar: tqdm[Any] | None,
    jobs: int,
    units: Callable[[str], int],
) -> Iterator[tuple[str, Any, float]]:
    """(name, fn(name, fmus[name], cfg, progress), wall s of that call) for every scene, in
    the order of `names`. With jobs > 1 the scenes run in that many processes at once, one
    scene per process at a time (each scene's timed runs stay in one process, so the ratios
    within a scene are taken under the same conditions); the bar then advances by
    units(name) when a scene's result arrives."""
    if jobs == 1 or len(names) < 2:
        for name in names:
            tic = time.perf_counter()
            result = fn(name, fmus[name], cfg, bar)
            yield name, result, time.perf_counter() - tic
        return
    with ProcessPoolExecutor(max_workers=min(jobs, len(names))) as pool:
        futures = [pool.submit(_timed, fn, name, fmus[name], cfg) for name in names]
        for name, future in zip(names, futures, strict=True):
            result, wall = future.result()
            if bar is not None:
                bar.update(units(name))
                bar.set_postfix_str(f"{name} done")
            yield name, result, wall


def show(bar: tqdm[Any] | None, what: str) -> None:
    """Name the task under way on the progress bar (if any), without advancing it."""
    if bar is not None:
        bar.set_postfix_str(what)


def advance(bar: tqdm[Any] | None, what: str = "") -> None:
    """Count one unit of work done on the progress bar (if any), naming it."""
    if bar is not None:
        bar.set_postfix_str(what, refresh=False)
        bar.update(1)


class FmuDriver:
    """One scene's FMU, instantiated once and reset between runs (fmi3Reset), stepped
    through fmpy. Runs a communication grid with the scene's input tables held per step.

    out_names/out_vrs: q[1..4], w_body[1..3], then the conserved energy output (has_E),
    L_world[1..3] (has_L) and for a free body x_cm[1..3] (has_x) where the FMU has them;
    inputs: the scene's inputs, vectors and scalars (all of them, in value-reference order);
    method_values: method name -> enumeration value, from the modelDescription."""

    def __init__(self, fmu_path: Path, scene: Scene):
        self.scene = scene
        self.inst = FmuInstance(fmu_path)
        self.method_values = self.inst.method_values
        names = set(self.inst.vr)
        # vector inputs (tau_body[1..3], ...) and scalar ones (a rotor's u_NAME, Omega_NAME, Omega_dot_NAME)
        self.inputs = [b for b in scene.input_names if f"{b}[1]" in names or b in names]
        e_name, _ = conserved_quantities(scene)
        self.out_names = [f"q[{k}]" for k in range(1, 5)] + [f"w_body[{k}]" for k in range(1, 4)]
        self.has_E = e_name is not None and e_name in names
        if self.has_E:
            self.out_names.append(e_name)
        self.has_L = "L_world[1]" in names
        if self.has_L:
            self.out_names += [f"L_world[{k}]" for k in range(1, 4)]
        self.has_x = scene.has("translation")
        if self.has_x:
            self.out_names += [f"x_cm[{k}]" for k in range(1, 4)]
        self.out_vrs = self.inst.value_references(self.out_names)
        self.in_vrs = {
            b: self.inst.value_references([b] if b in names else [f"{b}[{k}]" for k in range(1, 4)])
            for b in self.inputs
        }

    def close(self) -> None:
        """Free the instance and remove the extracted FMU."""
        self.inst.close()

    def start(self, method: str, h_max: float, stop_time: float) -> None:
        """Reset, choose the method and fixed steps of h_max (s) (tolerance 0, docs/theory.md
        §5.4), initialise for [0, stop_time]."""
        if method not in self.method_values:
            raise ValueError(f"method {method!r} is not in this FMU; it has {sorted(self.method_values)}")
        self.inst.reset()
        self.inst.set({"method": self.method_values[method], "tolerance": 0.0, "h_max": float(h_max)})
        self.inst.initialize(0.0, stop_time)

    def input_schedule(self, grid: np.ndarray) -> list[list[float] | None]:
        """Per communication interval: the input values (the scene's inputs in order, each
        held at its mean over the interval, ``Scene.input_mean``), or None when they equal
        the previous interval's. In batch mode the schedule is known in advance, and an
        input keeps its value until set again (FMI 3.0), so the master sets inputs only
        when a table switches."""
        out: list[list[float] | None] = []
        prev = None
        for t, t1 in itertools.pairwise(grid):
            u = [float(x) for b in self.inputs for x in self.scene.input_mean(b, float(t), float(t1))]
            out.append(None if u == prev else u)
            prev = u
        return out

    def run(self, method: str, h_max: float, grid: np.ndarray, record: bool) -> tuple[float, np.ndarray | None]:
        """Step over the grid; returns (wall s of the stepping loop, outputs (n, k) or None)."""
        sched = self.input_schedule(grid) if self.inputs else [None] * (len(grid) - 1)
        in_vrs = [v for b in self.inputs for v in self.in_vrs[b]]
        steps = [(float(a), float(b - a), u) for a, b, u in zip(grid[:-1], grid[1:], sched)]
        self.start(method, h_max, float(grid[-1]))
        do, get, setf = self.inst.step, self.inst.get_float64, self.inst.set_float64
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

    def accuracy(self, Y: np.ndarray, ref: Reference) -> tuple[float, float, float, float, float, float]:
        """(e_ω, e_R, e, E drift, L drift, |q| drift) of a recording run's outputs Y (rows:
        q, ω, then E, L, x_cm as the scene has them) against the reference."""
        k = 7
        E = Y[:, k] if self.has_E else None
        k += int(self.has_E)
        L = Y[:, k : k + 3] if self.has_L else None
        k += 3 * int(self.has_L)
        e_w, e_R, e = errors(Y[:, 4:7], Y[:, :4], ref, Y[:, k : k + 3] if self.has_x else None)
        return (e_w, e_R, e, *drifts(self.scene, E, L, np.linalg.norm(Y[:, :4], axis=1)))

    def median_wall(self, method: str, h_max: float, grid: np.ndarray, max_repeats: int) -> float:
        """Median wall time (s) of runs that read no outputs (measures.median_time)."""
        first = self.run(method, h_max, grid, record=False)[0]
        return median_time(lambda: self.run(method, h_max, grid, record=False)[0], first, max_repeats)

    def point(self, method: str, h_max: float, grid: np.ndarray, ref: Reference, max_repeats: int) -> Point:
        """Error, drift (recording run) and median wall time (runs without output reads)."""
        _, Y = self.run(method, h_max, grid, record=True)
        e_w, e_R, e, dE, dL, dq = self.accuracy(Y, ref)
        wall = self.median_wall(method, h_max, grid, max_repeats)
        return Point(f"h={h_max:.3g}", h_max, wall, e, e_w, e_R, dE, dL, dq, nominal_steps(grid, h_max))
