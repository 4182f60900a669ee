"""The error-control part of the report as a whole: run it, draw its figure, write its markdown section.

Runs rbcheck.workprecision.tolerance (error against tolerance, cost against fixed steps)
on every scene of the part and rbcheck.workprecision.tolerance_defaults (fast spin, the
scenes at their defaults), then `plot_tolerance` draws error against tolerance (one
panel per scene, one line per method) and `write_tolerance` the tables of report.md.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from modelsrc.methods import DEFAULT_TOLERANCE, ESTIMATE_FLOOR
from modelsrc.scene import load_scene

from .config import ERR_FLOOR, Config
from .harness import map_scenes
from .tolerance import (
    EPS,
    RESOLVED_FACTOR,
    RETIME_ROUNDS,
    SceneControl,
    controlled_methods,
    tolerance_scene,
    tolerance_scenes,
)
from .tolerance_defaults import TARGET_DRIFT, TARGET_ERROR, DefaultRun, default_scene, fast_spin

if TYPE_CHECKING:
    from tqdm import tqdm

# Target of the cost of error control: its wall time at most this many times the best fixed
# step's at the same error (median over the tolerances of a scene and method).
TARGET_CONTROL_COST = 1.3
# A scene and method where the controlled runs need this fraction of the fixed steps' work
# or less at the same error count as cheaper with error control (the step follows the
# motion's fast and slow phases).
CHEAPER = 0.9


@dataclass
class TolerancePart:
    """Everything the error-control part measured: per scene (`scenes`), the fast spins
    and the scenes at their defaults (`spins`, `defaults`)."""

    scenes: list[SceneControl] = field(default_factory=list)
    spins: list[DefaultRun] = field(default_factory=list)
    defaults: list[DefaultRun] = field(default_factory=list)


def tolerance_part(
    cfg: Config, fmus: dict[str, Path], out: Path, progress: tqdm[Any] | None, jobs: int = 1
) -> TolerancePart:
    """Measure the part on the FMUs `fmus` (scene -> path; the part's scenes and
    cfg.spin_scene), `jobs` scenes at a time (harness.map_scenes), and write its figure
    tolerance.png into `out`."""
    part = TolerancePart()
    names = tolerance_scenes(cfg)
    controlled = {s: len(controlled_methods(load_scene(s))) for s in names}
    for _, ctl, _ in map_scenes(tolerance_scene, names, fmus, cfg, progress, jobs, controlled.__getitem__):
        part.scenes.append(ctl)
    if cfg.spin_rates:
        part.spins = fast_spin(fmus[cfg.spin_scene], cfg, progress)
    for _, runs, _ in map_scenes(default_scene, names, fmus, cfg, progress, jobs, lambda name: 1):
        part.defaults += runs
    plot_tolerance(part.scenes, out / "tolerance.png")
    return part


def plot_tolerance(scenes: Sequence[SceneControl], path: Path) -> None:
    """Error at T against tolerance, log–log, one panel per scene, one line per method, with
    the line e = tolerance·T (what a tolerance per second promises) and 3× the reference's
    own error estimate."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ncol = min(4, max(1, len(scenes)))
    nrow = math.ceil(len(scenes) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.6 * ncol, 3.2 * nrow), squeeze=False, sharex=True)
    for ax, sc in zip(axes.flat, scenes):
        tols = [p.value for m in sc.methods for p in m.controlled.points]
        for m in sc.methods:
            pts = m.controlled.points
            if pts:
                ax.loglog(
                    [p.value for p in pts], [max(p.err, ERR_FLOOR) for p in pts], "o-", ms=3, lw=1, label=m.method
                )
        if tols:
            span = [min(tols), max(tols)]
            ax.loglog(span, [t * sc.T for t in span], "k--", lw=0.8, label="e = tolerance·T")
        if sc.ref.floor > 0:
            ax.axhline(RESOLVED_FACTOR * sc.ref.floor, color="r", ls=":", lw=0.8, label="3 × reference error")
        ax.set_title(f"{sc.name} (T = {sc.T:g} s)", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes.flat[len(scenes) :]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("tolerance (1/s)")
    for ax in axes[:, 0]:
        ax.set_ylabel("error e at T")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _g(x: float | None, spec: str = ".2g") -> str:
    """x formatted, n/a for None and NaN."""
    return "n/a" if x is None or not math.isfinite(x) else format(x, spec)


def method_bands(scenes: Sequence[SceneControl]) -> dict[str, tuple[float, float, int, dict[str, float]]]:
    """Per method: (min, max, count) of e/(tolerance·T) over the resolved runs of all
    scenes, and the scenes where it exceeds 1 (scene -> its largest ratio there)."""
    acc: dict[str, list[float]] = {}
    over: dict[str, dict[str, float]] = {}
    for sc in scenes:
        for m in sc.methods:
            r = [x for _, x, ok in m.ratios(sc.T, sc.ref.floor) if ok]
            acc.setdefault(m.method, []).extend(r)
            if r and max(r) > 1.0:
                over.setdefault(m.method, {})[sc.name] = max(r)
    return {k: (min(v), max(v), len(v), over.get(k, {})) for k, v in acc.items() if v}


def cost_summary(sc: SceneControl) -> list[tuple[str, float | None, float | None, float | None, int]]:
    """Per method: (name, median wall ratio, max wall ratio, median work ratio, count) of
    the controlled runs against the fixed ladder at equal error, over the runs whose error
    is resolved (≥ 3× the reference's estimate) and that the fixed ladder reached, not by
    its coarsest rung alone (there the fixed cost is only an upper bound)."""
    out = []
    for m in sc.methods:
        rows = [
            (wr, kr)
            for e, wr, kr, bound in m.cost_ratios()
            if wr is not None and kr is not None and not bound and e >= RESOLVED_FACTOR * sc.ref.floor
        ]
        if rows:
            walls, works = [r[0] for r in rows], [r[1] for r in rows]
            out.append((m.method, statistics.median(walls), max(walls), statistics.median(works), len(rows)))
        else:
            out.append((m.method, None, None, None, 0))
    return out


W = Callable[[str], None]


def write_tolerance(w: W, cfg: Config, part: TolerancePart) -> None:
    """The markdown of the part: definitions, targets, per-scene tables, fast spin, defaults."""
    w("## Error control: achieved error against tolerance, and its cost\n")
    w(
        "`tolerance` is a relative error per second (docs/theory.md §5.5): an internal step of h is accepted "
        "when its embedded estimate is at most tolerance·h/1 s, so the error after T seconds should be about "
        "tolerance·T. Each scene runs in batch mode (communication step T/10, or a tenth of an input's period) "
        "with h_max = 0 (no cap) at every tolerance 1e-3 … 1e-12, loosest first, until a run is predicted to take "
        f"more than {cfg.tol_cap:g} s; the fixed-step runs (tolerance = 0) are the batch part's h_max ladder with "
        "the same cap. e is the headline error of this report (max(e_ω/Ω, e_R), and e_x/X for a free body). "
        f"A run counts towards the bands when tolerance·T ≥ {RESOLVED_FACTOR:g}× the reference's own error "
        "estimate. Stop times shorter than the scene's are marked in the tables.\n"
    )
    w("![error against tolerance](tolerance.png)\n")
    bands = method_bands(part.scenes)
    if bands:
        lo, hi = min(v[0] for v in bands.values()), max(v[1] for v in bands.values())
        w(f"Band of e/(tolerance·T) over every scene, method and resolved tolerance: **{lo:.1e} … {hi:.2g}**.\n")
        w(
            "| method | min e/(tolerance·T) | max e/(tolerance·T) | resolved runs | scenes where e > tolerance·T "
            "(largest ratio) |\n|---|---:|---:|---:|---|"
        )
        for name, (a, b, n, over) in bands.items():
            where = ", ".join(f"{k} ({v:.2g})" for k, v in sorted(over.items(), key=lambda kv: -kv[1])) or "none"
            w(f"| {name} | {a:.1e} | {b:.2g} | {n} | {where} |")
        w("")
    _cost_table(w, part.scenes)
    for sc in part.scenes:
        _scene_table(w, sc)
    _defaults_table(w, "Fast spin at the defaults", part.spins, cfg)
    _defaults_table(w, "Every scene at its defaults", part.defaults, cfg)


def _cost_table(w: W, scenes: Sequence[SceneControl]) -> None:
    """Cost of error control against the best fixed step at the same error, per scene and method."""
    w("### Cost of error control against the best fixed step at equal error\n")
    w(
        "For each controlled run, the fixed-step ladder's wall time and internal steps are interpolated in "
        "log–log at the controlled run's error; the ratio is controlled / fixed (work: accepted + rejected "
        "internal steps against fixed steps, the same method, so the same cost per step). Median and largest "
        "over the tolerances whose error is resolved and that the fixed ladder reached with more than its coarsest "
        "rung (below that rung the fixed cost is only an upper bound). Target: median wall "
        f"ratio ≤ {TARGET_CONTROL_COST}. The wall times of both ladders are the fastest of up to {RETIME_ROUNDS} "
        "rounds that time every run of the method once, in turn (runs of a few ms timed alone carried the "
        "machine's second-to-second speed changes into the ratio); the work ratio carries no timing noise.\n"
    )
    w("| scene | method | median wall ratio | largest wall ratio | median work ratio | runs | ≤ 1.3 |")
    w("|---|---|---:|---:|---:|---:|---|")
    fails, cheaper = [], []
    for sc in scenes:
        for name, med, mx, work, n in cost_summary(sc):
            ok = "n/a" if med is None else ("yes" if med <= TARGET_CONTROL_COST else "NO")
            w(f"| {sc.name} | {name} | {_g(med)} | {_g(mx)} | {_g(work)} | {n} | {ok} |")
            if med is not None and med > TARGET_CONTROL_COST:
                fails.append(f"{sc.name} {name} {med:.2g}× (work {_g(work)}×)")
            if work is not None and work < CHEAPER:
                cheaper.append(f"{sc.name} {name} (work {work:.2g}×, wall {_g(med)}×)")
    w("")
    w(
        f"Median wall ratio above {TARGET_CONTROL_COST}: "
        + ("; ".join(fails) if fails else "none")
        + f". Error control cheaper than the best fixed step (median work ratio < {CHEAPER}): "
        + ("; ".join(cheaper) if cheaper else "none")
        + ".\n"
    )


def _scene_table(w: W, sc: SceneControl) -> None:
    """One scene: e and e/(tolerance·T) per tolerance and method, steps, and the ladder notes."""
    short = " (shortened from the scene's stop time)" if sc.shortened else ""
    w(f"### {sc.name}: error against tolerance\n")
    w(
        f"T = {sc.T:g} s{short}, communication step {sc.step:g} s ({sc.n_comm} steps). Reference: {sc.ref.source} "
        f"(own error ≈ {sc.ref.floor:.1e}). Cells: e, e/(tolerance·T) in brackets, accepted/rejected internal "
        "steps; '*': tolerance·T below 3× the reference's error (not in the band).\n"
    )
    tols = sorted({p.value for m in sc.methods for p in m.controlled.points}, reverse=True)
    w("| tolerance (1/s) | " + " | ".join(m.method for m in sc.methods) + " |")
    w("|---|" + "---|" * len(sc.methods))
    for tol in tols:
        cells = []
        for m in sc.methods:
            p = next((p for p in m.controlled.points if p.value == tol), None)
            if p is None:
                cells.append("—")
                continue
            flag = "" if tol * sc.T >= RESOLVED_FACTOR * sc.ref.floor else "*"
            cells.append(f"{p.err:.1e} ({p.err / (tol * sc.T):.2g}){flag}, {p.accepted}/{p.rejected}")
        w(f"| {tol:.0e} | " + " | ".join(cells) + " |")
    b = sc.band()
    w("")
    if b:
        w(f"Band of e/(tolerance·T) on {sc.name}: {b[0]:.1e} … {b[1]:.2g}.\n")
    notes = [f"{m.method}: {n}" for m in sc.methods for ln in (m.controlled, m.fixed) for n in ln.notes]
    if notes:
        w("Ladder notes: " + "; ".join(notes) + ".\n")


def _defaults_table(w: W, title: str, runs: Sequence[DefaultRun], cfg: Config) -> None:
    """Runs at default settings: errors, drifts, steps and whether the target is met."""
    if not runs:
        return
    w(f"### {title}\n")
    if title.startswith("Fast"):
        w(
            f"`{cfg.spin_scene}`'s body spun at ω0 (body frame), communication step {cfg.spin_step:g} s, "
            f"T = {cfg.spin_T:g} s, no step chosen by the user: the FMU's defaults, and rk8 at the default tolerance "
            f"{DEFAULT_TOLERANCE:g}. Reference: the closed form (Jacobi elliptic functions); its error column is the "
            "larger of ε·|ω0|·T (the rotation angle in double precision) and the change of the closed form's end "
            "state when ω0 moves by one ulp (the conditioning). The tennis racket at 1e4 rad/s over 1 s is the "
            "scene's racket over 1e4 s (time scales as 1/|ω0|), a thousand flips near the separatrix, where the "
            "elliptic modulus is close to 1: there the FMU's exact flow and rbcheck's closed form, two independent "
            "evaluations of the elliptic functions, are the only references (scipy DOP853 at rtol 1e-13 and 1e-12 "
            "differ from each other by 1e-7 there).\n"
        )
    else:
        w(
            "Each scene as shipped (its communication step, method, tolerance and h_max), against the report's "
            "reference on the same communication grid; rk8 at the default tolerance beside it where the default "
            "method is another.\n"
        )
    w(
        f"Target: e_ω/Ω and e_R ≤ {TARGET_ERROR:g}, relative E and |L| (or p_φ) drift ≤ {TARGET_DRIFT:g} "
        "(n/a: not conserved).\n"
    )
    w(
        "| case | setting | T (s) | e_ω/Ω | e_R (rad) | e | E drift | L drift | steps / rejected | wall (s) | "
        "reference error | met |"
    )
    w("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in runs:
        p = r.point
        w(
            f"| {r.case} | {r.setting} | {r.T:g} | {p.e_w / r.omega_scale:.1e} | {p.e_R:.1e} | "
            f"{p.err:.1e} | {_g(p.drift_E, '.1e')} | {_g(p.drift_L, '.1e')} | {p.accepted} / {p.rejected} | "
            f"{p.wall:.3g} | {r.ref_floor:.0e} | {'yes' if r.met else 'NO'} |"
        )
    w("")
    for r in runs:
        if not r.met:
            w(_miss_note(r, runs) + "\n")


def _miss_note(r: DefaultRun, runs: Sequence[DefaultRun]) -> str:
    """Why a run at default settings missed the target, from what it measured: the mean
    step, whether its tolerance (the point's) asked the steps for less than the estimates'
    round-off floor (modelsrc.methods.ESTIMATE_FLOOR), the flow's conditioning (the
    reference's error over ε), and whether the FMU's defaults met the target on the same case."""
    p = r.point
    h = r.T / max(p.accepted, 1)
    parts = [f"Not met: {r.case}, {r.setting}: e = {p.err:.1e} after {p.accepted} steps (mean step {h:.1e} s)"]
    if 0 < p.tolerance * h < ESTIMATE_FLOOR:
        parts.append(
            f"the tolerance asks each step for a relative error of {p.tolerance * h:.1e}, below the floor "
            f"{ESTIMATE_FLOOR:g} where the steps' error estimates are round-off (docs/theory.md §5.5), so the floor, "
            "not the tolerance, sets the step"
        )
    kappa = r.ref_floor / EPS
    if kappa > 1e3:
        parts.append(
            f"the flow amplifies a relative change of its state by up to about {kappa:.0e} (reference error / ε)"
        )
    if any(o.case == r.case and o.met and o.defaults for o in runs):
        parts.append("the FMU's defaults meet the target on the same case")
    return "; ".join(parts) + "."
