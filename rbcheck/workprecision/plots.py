"""Diagrams of the report (PNG): work-precision per scene, co-simulation time split, long-horizon energy drift."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .batch import SceneResult
from .config import ERR_FLOOR, LEVELS
from .cosim import CosimResult
from .long_horizon import LongRun


def _pyplot() -> Any:
    """matplotlib.pyplot on the Agg backend (files only, no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


STYLE = {"FMU": dict(ls="-", marker="o"), "Exudyn": dict(ls="--", marker="s"), "scipy": dict(ls=":", marker="^")}


def plot_scene(res: SceneResult, path: Path) -> None:
    """Work-precision diagram: headline error against wall time, log-log, one line per method."""
    plt = _pyplot()
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
    ax.set_title(f"{res.label}: T = {res.T:g} s, batch mode (communication step T/{round(res.T / res.step)})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_cosim(res: CosimResult, path: Path) -> None:
    """Co-simulation: error against total wall time, and the time split per run."""
    plt = _pyplot()
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
    plt = _pyplot()
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
