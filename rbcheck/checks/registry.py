r"""Registry of the checks of ``rbfmu check``, the report types, and the printed tables.

Two kinds of checks are registered here (by the modules that define them):

* scene-specific checks, one per scene name (``@scene_check("heavy_top")``): a function
  ``(fmu_path, scene, quick) -> CheckOutput`` with the rows only that scene has (e.g.
  nutation bounds against the closed form, docs/theory.md §4.2);
* generic checks (``@generic_check("FMU vs Exudyn trajectories")``): a function
  ``(fmu_path, scene, quick) -> GenericOutcome`` run for EVERY scene, shipped or given by
  path, which decides from the scene's data whether it applies and otherwise raises
  :class:`NotApplicable` with the reason, printed in the table.

:func:`scene_report` runs the scene's specific check (if one is registered) and every
generic check; a scene without a specific check still gets the generic ones.
:func:`format_report` prints the table. Units SI throughout; the rows name theirs.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from fmu.drive.run import RunResult
from modelsrc.scene import Scene

from ..numerics.rotation_np import quat_to_matrix, rotation_angle_between
from .common import NotApplicable, load

if TYPE_CHECKING:  # the generic checks import this module; types only, no import cycle
    from .tops import FastTopResult
    from .trajectories import DriftRow, TrajectoryComparison

__all__ = [
    "CheckOutput",
    "GenericCheck",
    "GenericOutcome",
    "NotApplicable",
    "Row",
    "SceneCheck",
    "SceneReport",
    "final_rows",
    "format_report",
    "generic_check",
    "generic_checks",
    "horizon",
    "registered_scenes",
    "scene_check",
    "scene_report",
    "trajectory_rows",
]


@dataclass
class Row:
    """One line of a scene table: values from the FMU, Exudyn and the closed form
    (nan where there is none) and a unit."""

    quantity: str
    unit: str
    fmu: float
    exudyn: float
    closed: float = float("nan")
    tol: float = float("nan")  # the largest |FMU - closed| (or FMU, closed nan) that passes; nan: no verdict

    @property
    def judged(self) -> bool:
        """True when the row carries a tolerance, so it passes or fails."""
        return bool(np.isfinite(self.tol))

    @property
    def measured(self) -> float:
        """What the tolerance bounds: |FMU − closed form|, or the FMU's value where there is no closed form."""
        return abs(self.fmu - self.closed) if np.isfinite(self.closed) else abs(self.fmu)

    @property
    def passed(self) -> bool:
        """True when the row is judged and its measured value is finite and within tol (nan fails)."""
        return self.judged and bool(np.isfinite(self.measured)) and self.measured <= self.tol


@dataclass
class CheckOutput:
    """What a scene-specific check returns: its table rows, a note for the table header
    (what the closed forms are), and details (result objects, e.g. ``"fast_top"``)."""

    rows: list[Row]
    note: str = ""
    details: dict[str, Any] = field(default_factory=dict)


@dataclass
class GenericOutcome:
    """What a generic check adds to a scene's report: table rows, the FMU-vs-Exudyn
    comparison, drift rows, a header note and a note for the drift table."""

    rows: list[Row] = field(default_factory=list)
    comparison: TrajectoryComparison | None = None
    drifts: list[DriftRow] = field(default_factory=list)
    note: str = ""
    drift_note: str = ""


@dataclass
class SceneReport:
    """Everything printed for one scene. not_applicable: generic check title -> why it
    does not apply to this scene (printed, never dropped); wall_time [s]."""

    scene: str
    note: str
    rows: list[Row]
    comparison: TrajectoryComparison | None
    drifts: list[DriftRow]
    details: dict[str, Any]
    wall_time: float
    drift_note: str = ""
    not_applicable: dict[str, str] = field(default_factory=dict)
    errors: dict[str, str] = field(default_factory=dict)  # check title -> why it could not run

    @property
    def judged_rows(self) -> int:
        """How many rows carry a tolerance (pass or fail)."""
        return sum(r.judged for r in self.rows)

    @property
    def exudyn_judged(self) -> bool:
        """True when the FMU-vs-Exudyn comparison ran with error estimates, so it passes or fails."""
        return self.comparison is not None and bool(np.isfinite(self.comparison.est_fmu_w))

    def failures(self) -> list[str]:
        """Why the scene does not pass, as sentences (empty when it passes): a judged row out of
        its tolerance, a check that could not run, an FMU-vs-Exudyn comparison beyond both
        sides' error estimates, or no check applied at all (every check not applicable)."""
        out = [f"check {t!r} could not run: {why}" for t, why in self.errors.items()]
        out += [
            f"{r.quantity}: measured {r.measured:.3e} {r.unit}, allowed {r.tol:.3e} {r.unit}"
            for r in self.rows
            if r.judged and not r.passed
        ]
        c = self.comparison
        if c is not None and self.exudyn_judged and not (c.max_dw <= c.tol_w and c.max_dangle <= c.tol_angle):
            out.append(
                f"FMU vs Exudyn: max|dw| {c.max_dw:.2e} rad/s (allowed {c.tol_w:.1e}), max attitude angle "
                f"{c.max_dangle:.2e} rad (allowed {c.tol_angle:.1e})"
            )
        if not (self.rows or self.comparison or self.drifts or self.errors):
            out.append(
                "no check applies to this scene, so nothing was checked (every check is listed as not applicable above)"
            )
        elif not (self.errors or self.judged_rows or self.exudyn_judged):
            out.append(
                "no row carries a tolerance and no FMU-vs-Exudyn comparison was judged, so nothing was checked "
                "against a bound (the rows are shown for reading; with fixed steps, tolerance 0, the FMU has no "
                "a-priori bound: set a tolerance)"
            )
        return out


SceneCheck = Callable[[Path, Scene, bool], CheckOutput]
GenericCheck = Callable[[Path, Scene, bool], GenericOutcome]


@dataclass(frozen=True)
class _Entry:
    fn: SceneCheck
    quick_stop_time: float | None


_SPECIFIC: dict[str, _Entry] = {}
_GENERIC: dict[str, GenericCheck] = {}  # title -> check, run in registration order


def scene_check(name: str, quick_stop_time: float | None = None) -> Callable[[SceneCheck], SceneCheck]:
    """Register the decorated function as the specific check of the scene ``name``.
    quick_stop_time [s]: horizon cap under ``--quick`` (for this check and the generic
    checks of this scene; see :func:`horizon`)."""

    def register(fn: SceneCheck) -> SceneCheck:
        if name in _SPECIFIC:
            raise ValueError(f"scene {name!r} already has a registered check ({_SPECIFIC[name].fn.__qualname__})")
        _SPECIFIC[name] = _Entry(fn, quick_stop_time)
        return fn

    return register


def generic_check(title: str) -> Callable[[GenericCheck], GenericCheck]:
    """Register the decorated function as a check run for every scene, under ``title``
    (the name printed when it does not apply)."""

    def register(fn: GenericCheck) -> GenericCheck:
        if title in _GENERIC:
            raise ValueError(f"generic check {title!r} is registered twice")
        _GENERIC[title] = fn
        return fn

    return register


FeatureTable = Callable[[Scene], list[tuple[str, GenericCheck]]]
_FEATURE_TABLES: list[FeatureTable] = []  # rbcheck.checks.feature_table.checks_for, registered on import


def feature_table(fn: FeatureTable) -> FeatureTable:
    """Register fn(scene) -> [(title, check)]: the checks of the features a scene uses, run by
    :func:`scene_report` for a scene without a specific check (rbcheck.checks.feature_table)."""
    _FEATURE_TABLES.append(fn)
    return fn


def registered_scenes() -> list[str]:
    """Names of the scenes with a registered specific check."""
    return sorted(_SPECIFIC)


def generic_checks() -> list[str]:
    """Titles of the generic checks, in the order they run."""
    return list(_GENERIC)


def has_specific_check(scene: Scene) -> bool:
    """True when a check is registered under the scene's name (the shipped scenes)."""
    return scene.name in _SPECIFIC


def horizon(scene: Scene, quick: bool) -> float:
    """Horizon [s] of the checks: the scene's stop_time, capped under ``quick`` by the
    quick_stop_time its specific check registered (unregistered scenes: stop_time, so a
    scene file for a quick check should have a short one)."""
    entry = _SPECIFIC.get(scene.name)
    if quick and entry is not None and entry.quick_stop_time is not None:
        return min(scene.stop_time, entry.quick_stop_time)
    return scene.stop_time


def final_rows(r: RunResult, e: dict[str, Any] | None, w_cf: NDArray | None = None) -> list[Row]:
    """Rows of the final body angular velocity [rad/s] (FMU run r, Exudyn run e, closed form
    w_cf; the Exudyn column nan where e is None: no Exudyn model of the scene)."""
    nan = float("nan")
    rows = []
    for k in range(3):
        rows.append(
            Row(
                f"w_body[{k + 1}](T)",
                "rad/s",
                float(r.vector("w_body")[-1, k]),
                float(e["w_body"][-1, k]) if e is not None else nan,
                float(w_cf[-1, k]) if w_cf is not None else nan,
            )
        )
    return rows


def trajectory_rows(r: RunResult, e: dict[str, Any] | None, w_cf: NDArray, q_cf: NDArray) -> list[Row]:
    """Rows of the largest deviation of each run from the closed-form trajectory: body
    rate [rad/s] and attitude angle [rad] (q_cf body -> world, sampled at r.time; the
    Exudyn column nan where e is None)."""
    wf, qf = r.vector("w_body"), r.vector("q")
    Rcf = quat_to_matrix(q_cf)
    nan = float("nan")
    return [
        Row(
            "max_t |w - w_closed|",
            "rad/s",
            float(np.max(np.abs(wf - w_cf))),
            float(np.max(np.abs(e["w_body"] - w_cf))) if e is not None else nan,
            0.0,
        ),
        Row(
            "max_t attitude angle to closed form",
            "rad",
            float(np.max(rotation_angle_between(quat_to_matrix(qf), Rcf))),
            float(np.max(rotation_angle_between(quat_to_matrix(e["q"]), Rcf))) if e is not None else nan,
            0.0,
        ),
    ]


def scene_report(scene: Scene | str | Path, fmu_path: str | Path, quick: bool = False) -> SceneReport:
    """Run the scene's specific check (if registered under its name), every generic check,
    and, for a scene without a specific check, the checks of every feature it uses
    (the table registered with :func:`feature_table`), and collect the rows. ``scene``: a Scene, a shipped name
    or a .toml path. A check that raises anything but NotApplicable is recorded in
    ``errors`` (it could not run), never dropped."""
    t0 = time.perf_counter()
    sc = load(scene)
    fmu_path = Path(fmu_path)
    entry = _SPECIFIC.get(sc.name)
    rep = SceneReport(sc.name, "", [], None, [], {}, 0.0)
    notes: list[str] = []
    if entry is not None:
        try:
            out = entry.fn(fmu_path, sc, quick)
            rep.rows += out.rows
            rep.details.update(out.details)
            notes += [out.note] if out.note else []
        except Exception as exc:
            rep.errors[f"{sc.name} (its own check)"] = _reason(exc)
    else:
        notes.append(f"{sc.name!r} is not a shipped scene: the generic checks and those of its features")
    checks = list(_GENERIC.items()) + ([] if entry is not None else [c for f in _FEATURE_TABLES for c in f(sc)])
    for title, check in checks:
        try:
            g = check(fmu_path, sc, quick)
        except NotApplicable as exc:
            rep.not_applicable[title] = str(exc)
            continue
        except Exception as exc:
            rep.errors[title] = _reason(exc)
            continue
        rep.rows += g.rows
        rep.comparison = g.comparison or rep.comparison
        rep.drifts += g.drifts
        rep.drift_note = g.drift_note or rep.drift_note
        if g.note:
            notes.append(g.note)
    rep.note = "; ".join(notes)
    rep.wall_time = time.perf_counter() - t0
    return rep


def _reason(exc: BaseException) -> str:
    """An exception as a reason in words: its message, with its type when that says more."""
    msg = str(exc).strip() or "no message"
    return msg if isinstance(exc, ValueError) else f"{type(exc).__name__}: {msg}"


def _fmt(x: float | None) -> str:
    if x is None or not np.isfinite(x):
        return "-"
    return f"{x:.10g}" if abs(x) >= 1e-3 or x == 0.0 else f"{x:.4e}"


def _fmtd(a: float, b: float) -> str:
    if not (np.isfinite(a) and np.isfinite(b)):
        return "-"
    return f"{a - b:+.2e}"


def _verdict(r: Row) -> str:
    if not r.judged:
        return ""
    return f"ok (<= {r.tol:.1e})" if r.passed else f"FAIL (> {r.tol:.1e})"


def _sentence(text: str) -> str:
    """text with a capital first letter and a full stop (it may already end in one)."""
    text = text.strip()
    text = text[:1].upper() + text[1:]
    return text if text.endswith((".", ")", "?", "!")) else text + "."


def _fast_top_lines(f: FastTopResult) -> list[str]:
    lines = ["fast top (theta0 from the scene, theta0' = phi0' = 0); err = approx/FMU - 1:"]
    lines.append(
        f"  {'w3':>6s} {'sigma':>7s} {'amp FMU':>11s} {'amp approx':>11s} {'err':>9s} "
        f"{'freq FMU':>10s} {'err':>9s} {'prec FMU':>10s} {'err':>9s} {'FMU/CF-1 max':>12s}"
    )
    for r in f.rows:
        cf = max(
            abs(r.amp_fmu / r.amp_closed - 1),
            abs(r.freq_fmu / r.freq_closed - 1),
            abs(r.prec_fmu / r.prec_closed - 1),
        )
        lines.append(
            f"  {r.w3:6.0f} {r.sigma:7.4f} {r.amp_fmu:11.5e} {r.amp_approx:11.5e} "
            f"{r.approx_error('amp'):+9.2e} {r.freq_fmu:10.4f} {r.approx_error('freq'):+9.2e} "
            f"{r.prec_fmu:10.5f} {r.approx_error('prec'):+9.2e} {cf:12.1e}"
        )
    lines.append(
        f"  log-log slope of amplitude vs w3: {f.slope_all:.4f} (all), {f.slope_asymptotic:.4f} "
        f"(sigma <= {f.sigma_max}: w3 = {', '.join(f'{w:g}' for w in f.asymptotic_w3)}); "
        f"expected -2"
    )
    return lines


def format_report(rep: SceneReport) -> str:
    """The printed table of one scene, then the comparison, drift and not-applicable lines."""
    lines = [f"== {rep.scene} ==  ({rep.note})"]
    hdr = (
        f"{'quantity':46s} {'unit':7s} {'FMU':>17s} {'Exudyn':>17s} {'closed form':>17s} "
        f"{'FMU-CF':>10s} {'Exu-CF':>10s} {'FMU-Exu':>10s}  verdict"
    )
    lines += [hdr, "-" * len(hdr)]
    for r in rep.rows:
        lines.append(
            f"{r.quantity:46s} {r.unit:7s} {_fmt(r.fmu):>17s} {_fmt(r.exudyn):>17s} "
            f"{_fmt(r.closed):>17s} {_fmtd(r.fmu, r.closed):>10s} {_fmtd(r.exudyn, r.closed):>10s} "
            f"{_fmtd(r.fmu, r.exudyn):>10s}  {_verdict(r)}"
        )
    c = rep.comparison
    if c is not None:
        lines.append(
            f"FMU vs Exudyn {c.exudyn_solver} over {c.stop_time:g} s: max|dw| {c.max_dw:.2e} rad/s (error estimates "
            f"FMU {c.est_fmu_w:.1e}, Exudyn {c.est_exu_w:.1e}), max attitude angle {c.max_dangle:.2e} rad "
            f"(estimates {c.est_fmu_angle:.1e}, {c.est_exu_angle:.1e})"
            + (
                f", max|dx_cm| {c.max_dx:.2e} m (estimates {c.est_fmu_x:.1e}, {c.est_exu_x:.1e})"
                if np.isfinite(c.max_dx)
                else ""
            )
        )
    if rep.drifts:
        names = list(rep.drifts[0].drifts)
        lines.append(
            "conserved-quantity drift, max_t |X(t) - X(0)| / scale:"
            + (f" ({rep.drift_note})" if rep.drift_note else "")
        )
        lines.append(f"  {'method':16s} {'h_max':>8s} " + " ".join(f"{n:>10s}" for n in names) + "   wall")
        for d in rep.drifts:
            lines.append(
                f"  {d.method:16s} {d.h_max:8.0e} "
                + " ".join(f"{d.drifts[n]:10.1e}" for n in names)
                + f"  {d.wall_time:5.2f}s"
            )
    if "fast_top" in rep.details:
        lines += _fast_top_lines(rep.details["fast_top"])
    for title, reason in rep.not_applicable.items():
        lines.append(f"not applicable: {title}: {_sentence(reason)}")
    for title, reason in rep.errors.items():
        lines.append(f"COULD NOT RUN: {title}: {_sentence(reason)}")
    fails = rep.failures()
    judged, exudyn = rep.judged_rows, rep.exudyn_judged
    reading = len(rep.rows) - judged
    if fails:
        lines.append(f"{rep.scene}: FAILED ({len(fails)} reason(s), {rep.wall_time:.1f} s):")
        lines += [f"  - {_sentence(f)}" for f in fails]
    else:  # failures() is not empty unless a row or the Exudyn comparison was judged
        within = [f"{judged} row(s)"] * bool(judged) + ["FMU vs Exudyn"] * exudyn
        lines.append(
            f"{rep.scene}: passed: {' and '.join(within)} within their tolerances; {reading} row(s) without one "
            f"(shown for reading) ({rep.wall_time:.1f} s)"
        )
    return "\n".join(lines)
