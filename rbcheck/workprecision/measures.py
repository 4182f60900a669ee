"""Measures of a report run: points and lines, the time at an error level, the fastest-method table, observed orders.

A `Point` is one run (cost and accuracy, defined in the rbcheck.workprecision docstring),
a `Line` one method over its ladder. Wall times at an error level are interpolated in
log–log along a line; where a line stops short, its most expensive run bounds the time
from below.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from .config import ERR_FLOOR, LEVELS


@dataclass
class Point:
    """One run of a line: its parameter, cost and accuracy (definitions in the
    rbcheck.workprecision docstring). value: h_max or h (s) of step ladders, rtol or tol
    of tolerance ladders; wall: s; err: headline error e (dimensionless); e_w: rad/s (body
    frame); e_R: rad; drift_*: relative E, relative L, max ||q| − 1| (NaN: not measured)."""

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


def _speedup(fmu: Best, other: Best) -> float | None:
    """other's time / the FMU's time; None when undefined or a bound in the wrong direction."""
    if fmu.time is None or fmu.lower_bound or other.time is None or other.upper_bound:
        return None
    return other.time / fmu.time


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
        rows.append(
            LevelRow(
                lev,
                fastest[1],
                fastest[0],
                b["FMU"],
                b["Exudyn"],
                b["scipy"],
                _speedup(b["FMU"], b["Exudyn"]),
                _speedup(b["FMU"], b["scipy"]),
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
        for a, b in itertools.pairwise(points)
        if low <= b.err and a.err <= high and a.value != b.value and b.wall >= 1.5 * a.wall
    ]
    return float(np.median(slopes)) if slopes else None


def nominal_steps(grid: np.ndarray, h: float) -> int:
    """Internal steps ⌈Δ_k/h⌉ summed over the communication intervals Δ_k (s), as the FMU
    (without its stiffness bound) and Exudyn's driver split them."""
    return int(sum(math.ceil((b - a) / h * (1 - 1e-12)) for a, b in itertools.pairwise(grid)))
