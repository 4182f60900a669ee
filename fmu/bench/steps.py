"""`rbfmu bench`: the generated step against the hand-written reference, and fmi3DoStep against the raw step.

Per shipped scene and method (rk4, rk8), in instructions (callgrind: they hold under load)
and CPU time (confirms them): the generated fixed step against fmu/c/bench_reference.c, the
yardstick an expert's kernel sets (targets: ≤ 1.15× in instructions, ≤ 1.2× in time), and
fmi3DoStep called from a C loop with 1 and with 10 internal steps per call against the raw
generated step (the layer's fixed cost per call; targets ≤ 1.3× and ≤ 1.1×). Times: the
harness (fmu/c/bench_step.c) and the reference run in separate processes, alternately
(A B A B ...); a ratio of times is taken within one pair (generated/reference) or within
one harness process (doStep/raw), and the table shows its median and spread over the pairs,
so that one badly placed process cannot decide a row.
"""

from __future__ import annotations

import dataclasses
import shutil
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from modelsrc.methods import METHODS, WORK_LIMIT
from modelsrc.scene import Scene, list_scenes, load_scene

from ..build.build_fmu import build_fmu
from . import instructions
from .benchmark import compile_harness, default_step, fmpy_step_us, harness_args, run_loops, work_limit_walls
from .reference import reference_args, reference_command, run_reference, start_state

REFERENCE_METHODS = ("rk4", "rk8")  # the methods fmu/c/bench_reference.c has: the FMU's fixed rk4 and rk8 steps
TARGET_INSTRUCTIONS = 1.15  # generated / reference, instructions per step (issue 35)
TARGET_TIME = 1.2  # generated / reference, CPU time per step
TARGET_DOSTEP_1 = 1.3  # a doStep of one internal step against the raw generated step
TARGET_DOSTEP_10 = 1.1  # a doStep of ten internal steps against ten raw generated steps
TARGET_NS = 150.0  # docs/report/report.md targets: <= 150 ns per RK4 internal step of the 7-state body
# The work-limit table: the cheapest right-hand side among the shipped scenes and the
# dearest (gravity), so that the wall time at the limit is bracketed.
WORK_LIMIT_SCENES = ("free_asymmetric", "heavy_top")
BENCH_PAIRS = 5  # pairs of processes (harness, reference) run alternately
BENCH_STEPS = 500_000  # RK4 steps each process times (best of 5 repeats inside it); RK8 a third
COUNT_STEPS = 2000  # callgrind: runs of N and 2N steps (RK8 half as many)


@dataclasses.dataclass(frozen=True)
class Counts:
    """Instructions per internal step (None without valgrind): the raw generated step in a C
    loop, one long fmi3DoStep, doSteps of 1 and of 10 internal steps from a C loop, the reference."""

    raw: float | None
    long: float | None
    loop1: float | None
    loop10: float | None
    ref: float | None


@dataclasses.dataclass(frozen=True)
class Interleaved:
    """ns of CPU time from processes run alternately: raw[k] (per generated step in a C loop),
    fmi[k] (per internal step of one long fmi3DoStep), loop1[k] and loop10[k] (per fmi3DoStep of
    1 and of 10 internal steps from a C loop) from the k-th harness process, ref[k] (per
    reference step) from the k-th reference process, which ran right after it."""

    raw: tuple[float, ...]
    fmi: tuple[float, ...]
    loop1: tuple[float, ...]
    loop10: tuple[float, ...]
    ref: tuple[float, ...]

    def ratio_spread(self, which: str = "ref") -> tuple[float, float, float]:
        """(min, median, max) over the pairs: raw/ref for "ref", else the doStep's cost per
        internal step over the raw step in the same process ("fmi", "loop1", "loop10")."""
        raw = np.asarray(self.raw)
        r = {"ref": raw / np.asarray(self.ref), "fmi": np.asarray(self.fmi) / raw,
             "loop1": np.asarray(self.loop1) / raw, "loop10": np.asarray(self.loop10) / (10 * raw)}[which]  # fmt: skip
        return float(r.min()), float(np.median(r)), float(r.max())

    def median(self, which: str) -> float:
        """Median ns of `which`: "raw", "fmi", "loop1", "loop10" or "ref"."""
        return float(np.median(getattr(self, which)))


def _ratio(a: float | None, b: float | None) -> float | None:
    return None if a is None or b is None else a / b


def step_counts(exe: Path, ref_cmd: list[str], method: str, h: float, n: int = COUNT_STEPS) -> Counts:
    """Instructions per internal step of the compiled harness `exe` in each of its modes and of
    the reference `ref_cmd` (`reference_command`), fixed steps of h (s) of `method`."""
    value = METHODS[method].value

    def harness(mode: str) -> float | None:
        return instructions.per_step(lambda k: harness_args(exe, mode, k, value, h), n)

    ref = instructions.per_step(lambda k: reference_args(ref_cmd, k, method, repeats=1), n)
    return Counts(harness("raw"), harness("long"), harness("loop1"), harness("loop10"), ref)


def interleaved_step_ns(
    fmu: Path, scene: Scene, method: str = "rk4", pairs: int = BENCH_PAIRS, n: int = BENCH_STEPS
) -> Interleaved:
    """The FMU's fixed `method` step ("rk4" or "rk8") at `default_step`, raw and through
    fmi3DoStep (`run_loops`), and the C reference of the scene's equations with the same
    method, each timed in `pairs` processes of n steps, run alternately (harness, reference,
    harness, ...): a slow spell of the machine then lands on both sides of a few pairs instead
    of deciding the ratio."""
    with tempfile.TemporaryDirectory() as tmp:
        return _interleaved(compile_harness(fmu, Path(tmp)), reference_command(scene, Path(tmp)), default_step(fmu),
                            method, pairs, n)  # fmt: skip


def _interleaved(exe: Path, ref_cmd: list[str], h: float, method: str, pairs: int, n: int) -> Interleaved:
    runs: list[tuple[float, ...]] = []
    for _ in range(pairs):
        runs.append((*run_loops(exe, n, METHODS[method].value, h), run_reference(ref_cmd, n, method)[0]))
    return Interleaved(*(tuple(r[i] for r in runs) for i in range(5)))


def bench_scene(fmu: Path, scene: Scene, method: str, pairs: int, n: int) -> tuple[Interleaved, Counts]:
    """Times (`interleaved_step_ns`) and instruction counts (`step_counts`) of one scene and
    method, the harness and the reference compiled once."""
    with tempfile.TemporaryDirectory() as tmp:
        exe, ref_cmd, h = compile_harness(fmu, Path(tmp)), reference_command(scene, Path(tmp)), default_step(fmu)
        counts = step_counts(exe, ref_cmd, method, h, COUNT_STEPS if method == "rk4" else COUNT_STEPS // 2)
        return _interleaved(exe, ref_cmd, h, method, pairs, n), counts


def _f(v: float | None, width: int, fmt: str = ".0f") -> str:
    return f"{'n/a':>{width}}" if v is None else f"{v:>{width}{fmt}}"


def _verdict(worst: float | None, target: float) -> str:
    return "not counted" if worst is None else ("met" if worst <= target else "NOT met")


def _worst(rows: list[tuple], key) -> tuple[float | None, str]:
    vals = [(key(r), f"{r[0]} {r[1]}") for r in rows if key(r) is not None]
    return max(vals) if vals else (None, "")


def print_tables(rows: list[tuple[str, str, Interleaved, Counts, float, int]]) -> None:
    """The two tables and their target lines; rows: (scene, method, times, counts, fmpy µs
    per doStep (NaN: not timed), states)."""
    if not instructions.have_valgrind():
        print(f"\ninstructions: {instructions.MISSING}")
    print("\nthe generated fixed step against the hand-written reference, per step "
          f"(instructions: target <= {TARGET_INSTRUCTIONS}x; CPU time: target <= {TARGET_TIME}x)")  # fmt: skip
    print(f"{'scene':<22}{'method':<7}{'instr gen':>10}{'ref':>7}{'gen/ref':>8}{'ns gen':>9}{'ref':>8}{'gen/ref':>8}"
          f"{'min..max':>12}")  # fmt: skip
    for name, method, iv, c, _, _ in rows:
        lo, mid, hi = iv.ratio_spread("ref")
        print(f"{name:<22}{method:<7}{_f(c.raw, 10)}{_f(c.ref, 7)}{_f(_ratio(c.raw, c.ref), 8, '.3f')}"
              f"{iv.median('raw'):9.1f}{iv.median('ref'):8.1f}{mid:8.3f}{f'{lo:.2f}..{hi:.2f}':>12}")  # fmt: skip
    print("\nfmi3DoStep from a C loop against the raw generated step (fixed steps of h, inputs held; doStep alone, "
          f"no get or set): per internal step (targets: 1 step per doStep <= {TARGET_DOSTEP_1}x, 10 steps <= "
          f"{TARGET_DOSTEP_10}x)")  # fmt: skip
    print(f"{'scene':<22}{'method':<7}{'instr raw':>10}{'doStep1':>8}{'ratio':>7}{'doStep10':>9}{'ratio':>7}"
          f"{'long':>7}{'ns raw':>8}{'doStep1':>8}{'ratio':>7}{'doStep10':>9}{'ratio':>7}{'long':>7}"
          f"{'fmpy us':>8}")  # fmt: skip
    for name, method, iv, c, us, _ in rows:
        r1, r10, rl = (iv.ratio_spread(w)[1] for w in ("loop1", "loop10", "fmi"))
        fmpy = f"{us:8.2f}" if np.isfinite(us) else f"{'':8}"
        print(f"{name:<22}{method:<7}{_f(c.raw, 10)}{_f(c.loop1, 8)}{_f(_ratio(c.loop1, c.raw), 7, '.2f')}"
              f"{_f(c.loop10, 9)}{_f(_ratio(c.loop10, c.raw), 7, '.2f')}{_f(_ratio(c.long, c.raw), 7, '.2f')}"
              f"{iv.median('raw'):8.1f}{iv.median('loop1'):8.1f}{r1:7.2f}{iv.median('loop10') / 10:9.1f}{r10:7.2f}"
              f"{rl:7.2f}{fmpy}")  # fmt: skip
    print("gen: the generated fixed step (no error estimate) in a C loop, the harness fmu/c/bench_step.c; ref: the "
          "hand-written C kernel of the same equations and method (fmu/c/bench_reference.c, benchmark only); "
          "doStep1, doStep10: fmi3DoStep of 1 and 10 internal steps (doStep10 per internal step), long: one doStep "
          "of all steps; fmpy: us per doStep + getFloat64 of the outputs at the scene's step, fixed RK4 steps. "
          "Instructions: callgrind, a run of 2N steps minus one of N. ns: CPU time, medians over "
          f"{BENCH_PAIRS} harness and reference processes run alternately (best of 5 repeats of {BENCH_STEPS:,} RK4 or "
          f"{BENCH_STEPS // 3:,} RK8 steps inside each; the doStep loops over a quarter of them); ratios: median of "
          "the ratios within a pair or a process, min..max over the pairs")  # fmt: skip
    # the ns target is for the 7-state body; a free body or a moving pivot has 13 states
    seven = [iv.median("fmi") for _, method, iv, _, _, nx in rows if nx == 7 and method == "rk4"]
    if seven:
        print(f"\ntarget <= {TARGET_NS:.0f} ns per RK4 internal step (one long doStep) of the 7-state body: worst "
              f"{max(seven):.1f} ns ({'met' if max(seven) <= TARGET_NS else 'NOT met'})")  # fmt: skip
    for what, key, target in (
        ("generated/reference instructions", lambda r: _ratio(r[3].raw, r[3].ref), TARGET_INSTRUCTIONS),
        ("generated/reference CPU time (median of pairs)", lambda r: r[2].ratio_spread("ref")[1], TARGET_TIME),
        ("doStep of 1 internal step / raw step, instructions", lambda r: _ratio(r[3].loop1, r[3].raw), TARGET_DOSTEP_1),
        ("doStep of 1 internal step / raw step, CPU time", lambda r: r[2].ratio_spread("loop1")[1], TARGET_DOSTEP_1),
        ("doStep of 10 internal steps / 10 raw steps, instructions", lambda r: _ratio(r[3].loop10, r[3].raw),
         TARGET_DOSTEP_10),
        ("doStep of 10 internal steps / 10 raw steps, CPU time", lambda r: r[2].ratio_spread("loop10")[1],
         TARGET_DOSTEP_10),
    ):  # fmt: skip
        worst, where = _worst(rows, key)
        shown = "n/a" if worst is None else f"{worst:.3f} ({where})"
        print(f"target {what} <= {target}: worst {shown}: {_verdict(worst, target)}")


def main(out_dir: str = "build/bench", scenes: Sequence[str] | None = None, work_limit: bool = True) -> int:
    """`rbfmu bench`: the tables of every shipped scene (or `scenes`) and, with `work_limit`,
    the work-limit table. Returns the exit status."""
    out = Path(out_dir)
    if shutil.which("gcc") is None:
        print("gcc is needed for the benchmark")
        return 1
    rows = []
    for name in scenes or list_scenes():
        # inputs at zero: a step costs the same for any input value, and a thrust or torque
        # held over the benchmark's steps would spin the body up until the sub-step limits
        # refuse the step
        sc = dataclasses.replace(load_scene(name), inputs={})
        fmu = build_fmu(sc, out)
        us = fmpy_step_us(fmu, sc.step, sc.fixed_step)
        for method in REFERENCE_METHODS:
            # DOP853's step is ~3 times RK4's: fewer steps keep the process times alike
            iv, counts = bench_scene(fmu, sc, method, BENCH_PAIRS, BENCH_STEPS if method == "rk4" else BENCH_STEPS // 3)
            rows.append((name, method, iv, counts, us if method == "rk4" else float("nan"), len(start_state(sc))))
            print(f"{name} {method}: generated {_f(counts.raw, 0)} instructions, {iv.median('raw'):.1f} ns; reference "
                  f"{_f(counts.ref, 0)}, {iv.median('ref'):.1f} ns", flush=True)  # fmt: skip
    print_tables(rows)
    if not work_limit:
        return 0
    print(f"\nthe longest doStep the default work_limit ({WORK_LIMIT:g} right-hand-side evaluations) admits:")
    print(f"{'scene':<16}{'method':<19}{'cost':>6}{'internal steps':>16}{'doStep s':>10}{'refusal us':>12}")
    for name in WORK_LIMIT_SCENES:
        sc = load_scene(name)
        for method, (steps, wall, refuse) in work_limit_walls(build_fmu(sc, out), sc).items():
            print(f"{name:<16}{method:<19}{METHODS[method].cost:>6g}{steps:>16,}{wall:>10.2f}{refuse * 1e6:>12.0f}")
    return 0
