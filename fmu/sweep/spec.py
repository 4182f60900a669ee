"""What a sweep runs: grids and random samples over an FMU's settable variables, checked against its modelDescription.

A sweep is a table of runs, one row per run and one column per variable set for it
(named as in the FMU: ``w_body[3]``, ``r_cm[3]``, ``method``). It comes from a grid
(`--param NAME=START:STOP:N`, the Cartesian product of every axis), from random samples
(`--sample NAME=normal(MEAN, STD) --samples N --seed S`), or from both (every sample at
every grid point: the same draws at each point). `Variables` says which names an FMU
lets a sweep set (start values of the states, parameters, inputs held constant) and
read (outputs); every bad value is a ModelInputError of one line naming it.
"""

from __future__ import annotations

import itertools
import math
import re
import sys
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from fmpy import read_model_description
from fmpy.model_description import ModelDescription

from modelsrc.errors import ModelInputError, finite_number, unknown_variable
from modelsrc.methods import METHODS, enumeration_value

from ..drive.options import split_assignment

# More runs than this in one sweep is almost surely a typo (and would not fit in memory as
# a table of runs); split such a study into several sweeps.
MAX_RUNS = 10_000_000
# What each settable kind of variable is, for messages and docs.
START_VALUE, PARAMETER, INPUT = "start value", "parameter", "input (held constant)"


def model_description(fmu_path: str | Path) -> ModelDescription:
    """The modelDescription of the FMU archive at `fmu_path`; a ModelInputError naming the
    file when it is not a zip archive or holds no readable modelDescription.xml."""
    try:
        return read_model_description(str(fmu_path))
    except zipfile.BadZipFile:
        raise ModelInputError(f"{fmu_path}: not an FMU (an FMU is a zip archive; this file is not one)") from None
    except KeyError:
        raise ModelInputError(f"{fmu_path}: not an FMU (the archive holds no modelDescription.xml)") from None
    except OSError as exc:
        raise ModelInputError(f"{fmu_path}: cannot be read: {exc.strerror or exc}") from None
    except Exception as exc:  # fmpy's parse and validation errors have no common type
        raise ModelInputError(
            f"{fmu_path}: its modelDescription.xml cannot be read ({type(exc).__name__}: {exc})"
        ) from None


def fmi3_model_description(fmu_path: str | Path) -> ModelDescription:
    """The modelDescription of an FMI 3.0 archive; a ModelInputError saying so (and how to
    get one) for any other FMI version, e.g. a scene built with `--fmi-version 2`."""
    md = model_description(fmu_path)
    if not str(md.fmiVersion).startswith("3"):
        raise ModelInputError(
            f"{fmu_path}: sweeps run FMI 3.0 FMUs, this one is FMI {md.fmiVersion}; build its scene as FMI 3.0 "
            "(rbfmu build SCENE, without --fmi-version 2) or sweep the scene itself (its name or .toml file)"
        )
    return md


@dataclass(frozen=True)
class Variables:
    """The variables of one FMU that a sweep may set and read (from its modelDescription).

    settable: name -> START_VALUE (states, initial="exact"), PARAMETER or INPUT;
    outputs: output names in value-reference order; methods: integrator name -> value of
    the `method` enumeration (the methods compiled into this FMU).
    """

    settable: dict[str, str]
    outputs: tuple[str, ...]
    methods: dict[str, int]

    @classmethod
    def of(cls, fmu_path: str | Path) -> Variables:
        """Read the variables of the FMU archive at `fmu_path`."""
        md = fmi3_model_description(fmu_path)
        settable: dict[str, str] = {}
        outputs: list[str] = []
        methods: dict[str, int] = {}
        for v in md.modelVariables:
            if v.causality == "output":
                outputs.append(v.name)
                if v.initial == "exact":
                    settable[v.name] = START_VALUE
            elif v.causality == "parameter":
                settable[v.name] = PARAMETER
            elif v.causality == "input":
                settable[v.name] = INPUT
            if v.name == "method" and v.declaredType is not None:
                methods = {item.name: int(item.value) for item in v.declaredType.items}
        return cls(settable, tuple(outputs), methods)

    @property
    def inputs(self) -> frozenset[str]:
        """The input variables (a sweep holds a swept input constant over the run)."""
        return frozenset(n for n, k in self.settable.items() if k == INPUT)

    def check_settable(self, name: str, where: str) -> None:
        """ModelInputError unless `name` may be set before a run; `where` names the option."""
        if name not in self.settable:
            raise unknown_variable(name, list(self.settable), known=self.outputs, where=where)

    def check_output(self, name: str, where: str) -> None:
        """ModelInputError unless `name` is an output of the FMU."""
        if name not in self.outputs:
            raise unknown_variable(name, self.outputs, self.settable, where, "outputs", "an output of this FMU")

    def method_value(self, value: object, where: str) -> float:
        """The enumeration value of a method given by name or value, if compiled in."""
        v = enumeration_value(value, self.methods)
        if v is None:
            allowed = ", ".join(f"{v} = {n}" for n, v in self.methods.items())
            raise ModelInputError(f"{where}: method {value!r} is not compiled into this FMU; allowed: {allowed}")
        return v


@dataclass(frozen=True)
class Axis:
    """One axis of a grid: a variable and its values (SI units of the variable); `log`:
    the values are spaced evenly in log (plots then use a log axis)."""

    name: str
    values: tuple[float | str, ...]
    log: bool = False


def parse_param(text: str) -> Axis:
    """`--param` syntax: NAME=START:STOP:N (N values, ends included), NAME=START:STOP:N:log
    (evenly spaced in log), or NAME=V1,V2,... (a list; for `method`, names or values)."""
    example = "NAME=START:STOP:N, NAME=START:STOP:N:log or NAME=V1,V2,... (e.g. 'w_body[3]=50:200:16')"
    name, rest, where = split_assignment(text, "--param", example)
    if ":" not in rest:
        items = [s.strip() for s in rest.split(",")]
        if any(not s for s in items):
            raise ModelInputError(f"{where}: empty value in the list; expected {example}")
        if name == "method":
            return Axis(name, tuple(items))
        return Axis(name, tuple(finite_number(s, where, "value") for s in items))
    parts = [s.strip() for s in rest.split(":")]
    log = len(parts) == 4 and parts[3] == "log"
    if len(parts) not in (3, 4) or (len(parts) == 4 and not log):
        raise ModelInputError(f"{where}: expected {example}")
    start, stop = finite_number(parts[0], where, "START"), finite_number(parts[1], where, "STOP")
    n = finite_number(parts[2], where, "N")
    if n != int(n) or n < 1:
        raise ModelInputError(f"{where}: N must be a whole number >= 1, got {parts[2]}")
    n = int(n)
    if n > MAX_RUNS:
        raise ModelInputError(f"{where}: N = {n} values; at most {MAX_RUNS} runs per sweep")
    if n > 1 and start == stop:
        raise ModelInputError(f"{where}: empty range: START = STOP = {parts[0]} with N = {n} > 1")
    if n == 1 and start != stop:
        raise ModelInputError(f"{where}: N = 1 takes START = STOP (one value), got {parts[0]} and {parts[1]}")
    if log:
        if start <= 0 or stop <= 0:
            raise ModelInputError(f"{where}: a log range needs START > 0 and STOP > 0")
        return Axis(name, tuple(float(v) for v in np.geomspace(start, stop, n)), log=True)
    return Axis(name, tuple(float(v) for v in evenly_spaced(start, stop, n)))


def evenly_spaced(start: float, stop: float, n: int) -> np.ndarray:
    """n values from start to stop (both included) evenly spaced: numpy's linspace, or where
    stop − start overflows (−1e308 to 1e308, issue 39.10) start·(1 − t) + stop·t, t = k/(n − 1),
    whose terms stay finite."""
    if math.isfinite(stop - start):
        return np.linspace(start, stop, n)
    t = np.arange(n) / (n - 1)
    values = start * (1.0 - t) + stop * t
    values[0], values[-1] = start, stop
    return values


@dataclass(frozen=True)
class Distribution:
    """A named distribution of one variable: uniform(a = LOW, b = HIGH),
    normal(a = MEAN, b = STD), loguniform(a = LOW, b = HIGH: log-uniform on [LOW, HIGH])."""

    name: str
    kind: str
    a: float
    b: float

    def draw(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """n draws from `rng` (one call, so the draws depend only on the seed and order)."""
        if self.kind == "uniform":
            return rng.uniform(self.a, self.b, n)
        if self.kind == "normal":
            return rng.normal(self.a, self.b, n)
        return np.exp(rng.uniform(math.log(self.a), math.log(self.b), n))


# numpy's standard normal draws (ziggurat, its tail from 53-bit uniforms) stay within ±13.7:
# normal(MEAN, STD) draws MEAN + STD·z, finite wherever |MEAN| + NORMAL_REACH·STD is.
NORMAL_REACH = 14.0
DISTRIBUTIONS = {"uniform": "uniform(LOW, HIGH)", "normal": "normal(MEAN, STD)", "loguniform": "loguniform(LOW, HIGH)"}
_DIST = re.compile(r"^(\w+)\s*\((.*)\)$")


def parse_sample(text: str) -> Distribution:
    """`--sample` syntax: NAME=uniform(LOW, HIGH), NAME=normal(MEAN, STD) or
    NAME=loguniform(LOW, HIGH)."""
    allowed = ", ".join(DISTRIBUTIONS.values())
    name, rest, where = split_assignment(text, "--sample", f"NAME=DIST(A, B) with DIST one of {allowed}")
    m = _DIST.match(rest)
    if not m or m.group(1) not in DISTRIBUTIONS:
        got = m.group(1) if m else rest
        raise ModelInputError(f"{where}: unknown distribution {got!r}; allowed: {allowed}")
    kind, args = m.group(1), [s.strip() for s in m.group(2).split(",")]
    if len(args) != 2 or not all(args):
        raise ModelInputError(f"{where}: {kind} takes two numbers: {DISTRIBUTIONS[kind]}")
    a, b = (finite_number(s, where, "argument") for s in args)
    if kind == "normal" and not b > 0:
        raise ModelInputError(f"{where}: normal(MEAN, STD) needs STD > 0, got {args[1]}")
    if kind != "normal" and not a < b:
        raise ModelInputError(f"{where}: {DISTRIBUTIONS[kind]} needs LOW < HIGH, got {args[0]}, {args[1]}")
    if kind == "loguniform" and not a > 0:
        raise ModelInputError(f"{where}: loguniform(LOW, HIGH) needs LOW > 0, got {args[0]}")
    # draws that would overflow (numpy refuses uniform's, normal's come out ±inf): refused here, naming the limit
    if kind == "uniform" and not math.isfinite(b - a):
        raise ModelInputError(
            f"{where}: uniform(LOW, HIGH) needs HIGH - LOW to be a finite number (at most {sys.float_info.max:.4g}); "
            f"{args[1]} - ({args[0]}) overflows"
        )
    if kind == "normal" and not math.isfinite(abs(a) + NORMAL_REACH * b):
        raise ModelInputError(
            f"{where}: normal(MEAN, STD) draws reach MEAN ± {NORMAL_REACH:g} STD, which must stay finite "
            f"(|MEAN| + {NORMAL_REACH:g} STD at most {sys.float_info.max:.4g}); with {args[0]}, {args[1]} they overflow"
        )
    return Distribution(name, kind, a, b)


def _check_count(n: int) -> None:
    if n > MAX_RUNS:
        raise ModelInputError(f"the sweep would have {n} runs; at most {MAX_RUNS} per sweep (split the study)")


def _unique(names: Sequence[str]) -> None:
    seen = set()
    for n in names:
        if n in seen:
            raise ModelInputError(f"variable {n} is swept twice (one --param or --sample per variable)")
        seen.add(n)


def grid(axes: Sequence[Axis] | Mapping[str, Sequence[float | str]]) -> pd.DataFrame:
    """The runs of a grid: the Cartesian product of the axes (the first varies slowest),
    one row per run. A mapping name -> values is taken as axes in its order."""
    if isinstance(axes, Mapping):
        axes = [Axis(n, tuple(v)) for n, v in axes.items()]
    _unique([a.name for a in axes])
    for a in axes:
        if len(a.values) == 0:
            raise ModelInputError(f"variable {a.name}: empty list of values")
    _check_count(math.prod(len(a.values) for a in axes))
    rows = list(itertools.product(*(a.values for a in axes)))
    return pd.DataFrame(rows, columns=[a.name for a in axes])


def check_seed(seed: object, where: str) -> None:
    """ModelInputError unless `seed` is a whole number >= 0 (what numpy's generators take)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ModelInputError(f"{where} {seed}: the seed must be a whole number >= 0")


def samples(dists: Sequence[Distribution], n: int, seed: int) -> pd.DataFrame:
    """n random runs: each variable drawn from its distribution, in the order given, from
    numpy's PCG64 generator seeded with `seed` (the same seed gives the same runs)."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ModelInputError(f"--samples must be a whole number >= 1, got {n}")
    _check_count(int(n))
    _unique([d.name for d in dists])
    check_seed(seed, "seed")
    rng = np.random.default_rng(seed)
    return pd.DataFrame({d.name: d.draw(rng, int(n)) for d in dists})


def plan(axes: Sequence[Axis], dists: Sequence[Distribution], n_samples: int | None, seed: int | None) -> pd.DataFrame:
    """The runs of a sweep: the grid, the samples, or every sample at every grid point."""
    if not axes and not dists:
        raise ModelInputError("nothing to sweep: give at least one --param or --sample")
    if dists and n_samples is None:
        raise ModelInputError("--sample needs --samples N (the number of random runs)")
    if n_samples is not None and not dists:
        raise ModelInputError("--samples needs at least one --sample NAME=DIST(A, B)")
    _unique([a.name for a in axes] + [d.name for d in dists])
    _check_count(math.prod(len(a.values) for a in axes) * (n_samples or 1))
    runs = grid(axes) if axes else pd.DataFrame(index=range(1))
    if dists:
        assert n_samples is not None and seed is not None
        drawn = samples(dists, n_samples, seed)
        runs = runs.merge(drawn, how="cross")
    return runs.reset_index(drop=True)


def check_runs(runs: pd.DataFrame, variables: Variables) -> pd.DataFrame:
    """The runs with every column checked against the FMU: settable names, finite numbers,
    methods compiled in (names replaced by their enumeration values). Returns a float table."""
    if len(runs) == 0 or len(runs.columns) == 0:
        raise ModelInputError("nothing to sweep: the table of runs has no rows or no columns")
    twice = runs.columns[runs.columns.duplicated()]
    if len(twice):
        raise ModelInputError(f"swept variable {twice[0]}: the table of runs has two columns of that name")
    out: dict[str, object] = {}
    for name in runs.columns:
        where = f"swept variable {name}"
        variables.check_settable(str(name), where)
        col = runs[name].tolist()
        if any(np.ndim(v) != 0 for v in col):
            shape = next(np.shape(v) for v in col if np.ndim(v) != 0)
            raise ModelInputError(
                f"{where}: every run needs one number, got a value of shape {shape} (a vector's components are "
                "swept as columns of their own, e.g. w_body[1])"
            )
        if name == "method":
            out[name] = [variables.method_value(v, where) for v in col]
            continue
        try:
            vals = np.asarray(col, dtype=float)  # the fast path for a large table
        except (TypeError, ValueError):
            vals = None
        if vals is None or not np.isfinite(vals).all():
            for v in col:
                finite_number(v, where)  # the one number check raises, naming the first bad value
        out[name] = vals if vals is not None else np.array([finite_number(v, where) for v in col])
    return pd.DataFrame(out, index=runs.index).astype(float)


def check_fixed(fixed: Mapping[str, float | str], variables: Variables, swept: Sequence[str]) -> dict[str, float]:
    """Values set the same for every run (`--set`): settable, finite, not also swept."""
    out = {}
    for name, v in fixed.items():
        where = f"--set {name}={v}"
        variables.check_settable(name, where)
        if name in swept:
            raise ModelInputError(f"{where}: {name} is also swept; set it or sweep it, not both")
        if name == "method":
            out[name] = variables.method_value(v, where)
            continue
        out[name] = finite_number(v, where)
    return out


def method_names(values: Sequence[float]) -> list[str]:
    """Method names of enumeration values (for plots and tables): METHODS' names."""
    by_value = {m.value: m.name for m in METHODS.values()}
    return [by_value.get(int(v), str(v)) for v in values]
