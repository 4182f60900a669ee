"""A rotor scene's cost against a spacecraft simulator's RK4 step: how many times faster the FMU reaches each error.

Spacecraft attitude simulators step a hub with three reaction wheels in about 15 µs with
a fixed-step RK4 (the figure issue 28 quotes for them). At equal error, such a simulator
needs the steps that an RK4 of the same equations needs; the FMU's own `rk4` line is that
RK4 (same method, same equations, same communication grid), so its internal steps at an
error level, interpolated in log–log between its rungs like the wall times
(measures.time_at_level) and at least one per communication step (the simulator writes
the same points), times 15 µs is the simulator's time; the FMU's is the fastest
FMU line's wall time at that level (any method). Only resolved levels count (the
reference must see the error).
"""

from __future__ import annotations

from dataclasses import dataclass

from .batch import SceneResult
from .measures import time_at_level

# s per fixed RK4 step of a hub with three wheels in a spacecraft simulator (issue 28)
SIMULATOR_STEP_S = 15e-6


@dataclass
class SimulatorRow:
    """One error level: RK4 steps needed (interpolated; `at_most`: the coarsest rung
    already met it, so fewer might do), the simulator's time (s) at SIMULATOR_STEP_S per
    step, the FMU's fastest time (s; `fmu_upper`: its line's coarsest rung already met the
    level, so it might be faster) and line, and simulator / FMU."""

    level: float
    steps: float
    at_most: bool
    fmu_upper: bool
    simulator_s: float
    fmu_s: float
    fmu_line: str
    ratio: float


def simulator_rows(res: SceneResult) -> list[SimulatorRow]:
    """The comparison at every resolved level that both the FMU's rk4 line and its fastest
    line reach; empty when the scene has no `FMU rk4` line."""
    rk4 = next((ln for ln in res.lines if ln.name == "FMU rk4"), None)
    if rk4 is None:
        return []
    rows = []
    for row in res.table:
        if not row.resolved or row.fmu.time is None or row.fmu.line is None or row.fmu.lower_bound:
            continue
        need = time_at_level([(float(p.work), p.err) for p in rk4.points if p.work > 0], row.level)
        if need is None or (need[1] and row.fmu.upper_bound):  # both sides bounds the other way: no ratio
            continue
        steps, at_most = need
        # the simulator writes the same communication points, so it takes at least one step
        # per communication step: where rk4's coarsest rung already met the level with that
        # many steps, the count is exact, not a bound
        if steps <= res.n_comm:
            steps, at_most = float(res.n_comm), False
        sim = steps * SIMULATOR_STEP_S
        rows.append(
            SimulatorRow(row.level, steps, at_most, row.fmu.upper_bound, sim, row.fmu.time, row.fmu.line,
                         sim / row.fmu.time)
        )  # fmt: skip
    return rows


def simulator_markdown(res: SceneResult, n_rotors: int) -> list[str]:
    """The report's lines on a rotor scene (n_rotors wheels or rotors): the rule and one
    row per level; nothing when no level qualifies."""
    rows = simulator_rows(res)
    if not rows:
        return []
    lines = [
        f"Against a spacecraft simulator stepping a hub with wheels at ~{SIMULATOR_STEP_S * 1e6:.0f} µs per fixed RK4 "
        f"step (the figure quoted for a hub with three wheels; this scene has {n_rotors}): at equal error it needs the "
        "steps the FMU's own rk4 line needed (the same method on the same equations), interpolated between rungs; the "
        "FMU's time is its fastest line's at that level (rbcheck/workprecision/simulator_compare.py).\n",
        "| error level | RK4 steps needed | simulator at 15 µs/step (s) | FMU fastest (s) | FMU line | FMU faster by |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        steps = f"≤ {r.steps:.0f}" if r.at_most else f"{r.steps:.0f}"
        ratio = f"≤ {r.ratio:.0f}×" if r.at_most else f"≥ {r.ratio:.0f}×" if r.fmu_upper else f"{r.ratio:.0f}×"
        lines.append(f"| {r.level:.0e} | {steps} | {r.simulator_s:.3g} | {r.fmu_s:.3g} | {r.fmu_line} | {ratio} |")
    lines.append("")
    return lines
