"""Summary figures of one sweep run: final values, extremes, first crossings of outputs, and the run summary's drifts.

A figure is written `end(NAME)` (the output's value at the stop time), `max(NAME)`,
`min(NAME)` (over the communication points), or `cross(NAME, LEVEL)`: the first time
(s) the output reaches LEVEL from the side it started on, interpolated linearly between
the two communication points around it (NaN if it never does before the stop time; 0
if it starts at LEVEL). A bare NAME means `end(NAME)`. Every run also records its final
state (`end(q[k])`, `end(w_body[k])`) and, from fmu.drive.summary.summarize, the drifts of E
and |L| where the scene conserves them (Scene.conserves_energy / Scene.torque_free) and
max ||q| − 1| (`E_drift`, `L_drift`, `qnorm_err`). The column of a figure is its
canonical text, so a table says what each column is.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from modelsrc.errors import ModelInputError

from ..drive.run import RunResult
from ..drive.summary import summarize
from .spec import Variables

KINDS = ("end", "max", "min", "cross")
# fmu.drive.summary.summarize's invariant figures kept per run (its docstring defines them).
SUMMARY_COLUMNS = ("E_drift", "L_drift", "qnorm_err")
STATE_BASES = ("q", "w_body")
_CALL = re.compile(r"^(\w+)\s*\((.*)\)$")


def _level_text(level: float) -> str:
    short = f"{level:g}"
    return short if float(short) == level else repr(level)


@dataclass(frozen=True)
class Figure:
    """One figure of a run: `kind` (one of KINDS) of output `name`; `level` for cross."""

    kind: str
    name: str
    level: float | None = None

    @property
    def column(self) -> str:
        """The column name: the figure's canonical text, e.g. `cross(w_body[2], 0)`."""
        if self.kind == "cross":
            assert self.level is not None
            return f"cross({self.name}, {_level_text(self.level)})"
        return f"{self.kind}({self.name})"


def parse_figure(text: str) -> Figure:
    """`end(NAME)`, `max(NAME)`, `min(NAME)`, `cross(NAME, LEVEL)` or a bare NAME."""
    allowed = "end(NAME), max(NAME), min(NAME), cross(NAME, LEVEL) or NAME"
    s = text.strip()
    m = _CALL.match(s)
    if m is None or m.group(1) not in KINDS:
        if m is not None and "[" not in m.group(1):
            raise ModelInputError(f"figure {text!r}: unknown function {m.group(1)!r}; allowed: {allowed}")
        if not s or any(c in s for c in "(),"):
            raise ModelInputError(f"figure {text!r}: expected {allowed}")
        return Figure("end", s)
    kind, args = m.group(1), [a.strip() for a in m.group(2).rsplit(",", 1)] if "," in m.group(2) else [m.group(2)]
    if kind == "cross":
        if len(args) != 2 or not args[0]:
            raise ModelInputError(f"figure {text!r}: cross takes an output and a level: cross(NAME, LEVEL)")
        try:
            level = float(args[1])
        except ValueError:
            raise ModelInputError(f"figure {text!r}: level {args[1]!r} is not a number") from None
        if not math.isfinite(level):
            raise ModelInputError(f"figure {text!r}: level must be finite")
        return Figure(kind, args[0], level)
    if len(args) != 1 or not args[0].strip():
        raise ModelInputError(f"figure {text!r}: {kind} takes one output: {kind}(NAME)")
    return Figure(kind, args[0].strip())


def standard_figures(variables: Variables) -> list[Figure]:
    """The final state of every run: end(q[k]) and end(w_body[k]) (those the FMU outputs)."""
    return [Figure("end", n) for n in variables.outputs if n.split("[")[0] in STATE_BASES]


def figures_for(texts: Sequence[str], variables: Variables) -> tuple[Figure, ...]:
    """The figures of a sweep: the final state, then those asked for (duplicates dropped),
    each checked to name an output of the FMU."""
    out: list[Figure] = standard_figures(variables)
    for t in texts:
        f = parse_figure(t)
        variables.check_output(f.name, f"figure {t!r}")
        if f not in out:
            out.append(f)
    return tuple(out)


def outputs_to_read(figures: Sequence[Figure], variables: Variables) -> tuple[str, ...]:
    """The outputs read at every communication point: those the figures and
    fmu.drive.summary.summarize need (q, w_body, E_total or E_kin, E_jacobi, L_world), in FMU order."""
    want = {f.name for f in figures}
    bases = {"q", "w_body", "L_world"}
    energy = {"E_total" if "E_total" in variables.outputs else "E_kin", "E_jacobi"}  # E_jacobi: an orbit's
    return tuple(n for n in variables.outputs if n in want or n in energy or n.split("[")[0] in bases)


def first_crossing(t: np.ndarray, y: np.ndarray, level: float) -> float:
    """First time (s) y reaches `level` from the side of y[0], linear between samples;
    0 if y[0] == level, NaN if it never does (or y is not finite there)."""
    d = np.asarray(y, dtype=float) - level
    side = np.sign(d[0])
    if side == 0:
        return float(t[0])
    hit = np.flatnonzero(np.sign(d) != side)
    if hit.size == 0:
        return math.nan
    i = int(hit[0])
    d0, d1 = d[i - 1], d[i]
    if not (np.isfinite(d0) and np.isfinite(d1)):
        return math.nan
    return float(t[i - 1] + (t[i] - t[i - 1]) * d0 / (d0 - d1))


def evaluate(result: RunResult, figures: Sequence[Figure]) -> dict[str, float]:
    """Every figure of one run, and summarize's invariant figures (SUMMARY_COLUMNS)."""
    row: dict[str, float] = {}
    for f in figures:
        y = result.values[f.name]
        if f.kind == "end":
            row[f.column] = float(y[-1])
        elif f.kind == "max":
            row[f.column] = float(np.max(y))
        elif f.kind == "min":
            row[f.column] = float(np.min(y))
        else:
            assert f.level is not None
            row[f.column] = first_crossing(result.time, y, f.level)
    s = summarize(result)
    row.update({c: float(s[c]) for c in SUMMARY_COLUMNS})
    return row
