"""Long-horizon run of the report: every FMU method on a free body for millions of steps, and its invariant drift."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from modelsrc.methods import METHODS, WORK_LIMIT
from modelsrc.scene import load_scene

from .config import Config
from .harness import FmuDriver, advance, show
from .references import drifts

if TYPE_CHECKING:
    from tqdm import tqdm


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


def run_method(drv: FmuDriver, method: str, cfg: Config) -> LongRun:
    """One method at the scene's h_max (s) for cfg.long_steps internal steps in
    cfg.long_chunks doSteps, outputs read at every doStep boundary. The wall time counts
    the doSteps only; after the first tenth of the chunks, a run projected beyond
    cfg.long_budget s stops and says so in its note."""
    h = float(drv.scene.fixed_step)
    planned = cfg.long_steps
    per_chunk = planned // cfg.long_chunks
    H = per_chunk * h
    drv.start(method, h, planned * h)
    # doSteps of per_chunk internal steps are deliberate: allow their work (with room for
    # refinements), which for gauss6 exceeds the default work_limit
    drv.inst.set({"work_limit": max(WORK_LIMIT, 4.0 * per_chunk * METHODS[method].cost)})
    do, get = drv.inst.step, drv.inst.get_float64
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
    E = Y[:, 7]  # out_names: q (4), w_body (3), E_kin, L_world (3)
    L = Y[:, 8:11]
    dE, dL, dq = drifts(drv.scene, E, L, np.linalg.norm(Y[:, :4], axis=1))
    t = np.arange(len(rows)) * H
    return LongRun(method, h, steps, planned, wall, dE, dL, dq, t, np.abs(E - E[0]) / E[0], note)


def long_horizon(fmu_path: Path, cfg: Config, progress: tqdm[Any] | None) -> list[LongRun]:
    """Each FMU method on cfg.long_scene (free_asymmetric) at its h_max for long_steps
    internal steps in long_chunks doSteps; a method whose first tenth projects beyond
    long_budget s (the Gauss methods: Newton iterations per step) stops there, at a tenth,
    and says so."""
    sc = load_scene(cfg.long_scene)
    out: list[LongRun] = []
    drv = FmuDriver(fmu_path, sc)
    try:
        if not (drv.has_E and drv.has_L):
            raise ValueError(f"long-horizon scene {sc.name} must be a free body with outputs E_kin and L_world")
        for m in sc.methods:
            show(progress, f"long horizon: {m}")
            out.append(run_method(drv, m, cfg))
            advance(progress, f"long horizon: {m}")
    finally:
        drv.close()
    return out
