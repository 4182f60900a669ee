"""The three-wheel gyrostat against a spacecraft simulator's 15 µs RK4 step: compute at equal error.

Spacecraft attitude simulators step a hub with three reaction wheels in about 15 µs with
a fixed-step RK4 (the figure issue 28 quotes for them). At equal error such a simulator
needs the steps that an RK4 of the same equations needs: the FMU's own `rk4` line is that
RK4 (same method, same equations, same communication grid), so its internal steps at an
error level, interpolated in log–log between its rungs like the wall times
(measures.time_at_level), and at least one per communication step (the simulator writes
the same points), times 15 µs is the simulator's compute. The FMU's is the cheapest of its
methods at that level: the internal steps its line needed, times that method's cost per
internal step through fmi3DoStep in C (the report's C step cost part, measured in the
same run). The Python driver's per-communication-point cost is left out on both sides;
the FMU's measured wall time, which includes it, is shown beside. Only resolved levels
count (the reference must see the error).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from .batch import SceneResult
from .measures import time_at_level

# s per fixed RK4 step of a hub with three wheels in a spacecraft simulator (issue 28)
SIMULATOR_STEP_S = 15e-6


@dataclass
class SimulatorRow:
    """One error level: RK4 steps needed (`at_most`: the coarsest rung with more than one
    step per communication step already met it, so fewer might do), the simulator's
    compute (s) at SIMULATOR_STEP_S per step, the FMU's cheapest method, its internal
    steps and compute (s, C cost per step through fmi3DoStep), the FMU's measured wall
    time of the fastest line (s, with the Python driver), and simulator / FMU compute."""

    level: float
    steps: float
    at_most: bool
    simulator_s: float
    method: str
    fmu_steps: float
    fmu_s: float
    fmu_wall: float
    ratio: float


def _steps_at(line_points: list[tuple[float, float]], level: float, floor: int) -> tuple[float, bool] | None:
    """(internal steps, at_most) of a line at an error level: interpolated, at least `floor`."""
    need = time_at_level(line_points, level)
    if need is None:
        return None
    steps, at_most = need
    if steps <= floor:  # one step per communication step is the least anyone writing those points takes
        return float(floor), False
    return steps, at_most


def simulator_rows(res: SceneResult, step_ns: Mapping[str, float]) -> list[SimulatorRow]:
    """The comparison at every resolved level that the FMU's rk4 line and one of its lines
    with a C step cost (step_ns: method -> ns per internal step through fmi3DoStep) reach."""
    lines = {ln.name.removeprefix("FMU "): ln for ln in res.lines if ln.family == "FMU"}
    rk4 = lines.get("rk4")
    if rk4 is None:
        return []
    rows = []
    for row in res.table:
        if not row.resolved or row.fmu.time is None:
            continue
        need = _steps_at([(float(p.work), p.err) for p in rk4.points if p.work > 0], row.level, res.n_comm)
        if need is None or need[1]:  # an upper bound on the simulator's work is no speed-up figure
            continue
        best: tuple[float, str, float] | None = None
        for method, ln in lines.items():
            if method not in step_ns:
                continue
            got = _steps_at([(float(p.work), p.err) for p in ln.points if p.work > 0], row.level, res.n_comm)
            if got is None:
                continue
            cost = got[0] * step_ns[method] * 1e-9
            if best is None or cost < best[0]:
                best = (cost, method, got[0])
        if best is None:
            continue
        sim = need[0] * SIMULATOR_STEP_S
        rows.append(SimulatorRow(row.level, need[0], need[1], sim, best[1], best[2], best[0], row.fmu.time,
                                 sim / best[0]))  # fmt: skip
    return rows


def simulator_markdown(res: SceneResult, step_ns: Mapping[str, float]) -> list[str]:
    """The report's lines on the three-wheel scene: the rule and one row per level;
    nothing when no level qualifies."""
    rows = simulator_rows(res, step_ns)
    if not rows:
        return []
    lines = [
        f"Against a spacecraft simulator stepping a hub with three wheels at ~{SIMULATOR_STEP_S * 1e6:.0f} µs per "
        "fixed RK4 step: at equal error it needs the steps the FMU's own rk4 line needed (the same method on the same "
        "equations; interpolated between rungs, at least one per communication step); the FMU's compute is its "
        "cheapest method's internal steps at that level times that method's C cost per internal step through "
        "fmi3DoStep (the C step cost table of this report). The last column is the FMU's measured wall time of its "
        "fastest line, with the Python driver's per-point cost (rbcheck/workprecision/simulator_compare.py).\n",
        "| error level | RK4 steps needed | simulator at 15 µs/step (s) | FMU method | its steps | FMU compute (s) "
        "| FMU step work smaller by | FMU wall with driver (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r.level:.0e} | {r.steps:.0f} | {r.simulator_s:.3g} | {r.method} | {r.fmu_steps:.0f} | "
            f"{r.fmu_s:.3g} | {r.ratio:.0f}× | {r.fmu_wall:.3g} |"
        )
    lines.append("")
    return lines
