"""`rbfmu bench --master`: a closed-loop communication step in ECOS (and libcosim) against the FMUs' own doSteps.

Per shipped system, counted by callgrind in one master run of the whole system (n = stop
time / H communication steps) minus a run of 0 steps (the same set-up, init and free: the
difference is the n steps alone, setup cancelled exactly):
  - all instructions of the process, the master's threads included (ECOS steps its FMUs in
    a TBB parallel_for; valgrind runs the threads one at a time and counts them all);
  - the instructions inside fmi2DoStep alone (`--toggle-collect=fmi2DoStep`: counting on only
    while a doStep of either FMU runs, its callees included), in the same kind of run: the
    FMUs' own doStep cost on the very trajectory the master runs (the plant's error-controlled
    steps depend on the motion, so a loop with the inputs held would time a different doStep).
The ratio all / doSteps is item 6's overhead (target ≤ 1.5×); 1 would be a master that
costs nothing. The master is driven by one call for the n steps (ecospy `step(n)`,
libcosimpy `step(n)`), so no Python runs between steps. CPU times per step (best of 3 runs,
the process's CPU time: the TBB worker's too) are printed beside the counts for context; they
vary with the machine's load. The doSteps' count is exact from run to run; the total is not
quite: the masters' worker threads wait for work, and how much they count while waiting
depends on scheduling (the slew in ECOS: 26 470 and 33 457 per step in two runs).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from ..bench import instructions
from .archive import open_archive
from .build import build_system
from .masters import load_tbb

SYSTEMS = ("slew", "quadrotor_hover")
MASTER_RUNNERS = ("ecos", "libcosim")
TARGET_OVERHEAD = 1.5  # issue 37 item 6: a closed-loop step in ECOS <= 1.5x the two FMUs' doSteps


@dataclass(frozen=True)
class MasterCost:
    """One system in one master: n communication steps; instructions per step of the whole
    process (`total`) and inside fmi2DoStep of either FMU (`dostep`), None without valgrind;
    CPU µs per step of the master's run (best of 3)."""

    system: str
    master: str
    n: int
    total: float | None
    dostep: float | None
    cpu_us: float

    @property
    def ratio(self) -> float | None:
        """total / dostep: the closed-loop step against the FMUs' own doSteps."""
        return None if self.total is None or not self.dostep else self.total / self.dostep


def run_steps(archive_path: str, master: str, n: int) -> float:
    """Open the archive in `master`, initialise, take n communication steps in one call,
    free; returns the CPU seconds of the steps (the process's, all threads). What callgrind
    counts (`_probe_command`) and what the times come from."""
    archive = open_archive(archive_path)
    if master == "ecos":
        load_tbb()
        from ecospy.EcosSimulation import EcosSimulation

        sim = EcosSimulation(archive.step, ssp_path=str(archive.path))
        if not sim.init(parameter_set=archive.parameter_set_name):
            raise RuntimeError(f"{archive_path}: ECOS could not initialise the system")
        tic = time.process_time()
        if n:
            sim.step(n)
        cpu = time.process_time() - tic
        sim.terminate()
        sim.free()
        return cpu
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.ERROR)
    ex = CosimExecution.from_ssp_file(str(archive.path), round(archive.step * 1e9))
    tic = time.process_time()
    if n and not ex.step(n):
        raise RuntimeError(f"{archive_path}: libcosim's steps failed")
    return time.process_time() - tic


def _probe_command(archive: Path, master: str, n: int) -> list[str]:
    code = f"from fmu.system.overhead import run_steps; run_steps({str(archive)!r}, {master!r}, {n})"
    return [sys.executable, "-c", code]


def _count(archive: Path, master: str, n: int, toggle: bool) -> float:
    """Instructions per step: a run of n steps minus a run of 0 (PYTHONHASHSEED fixed so
    that the interpreter's own work is the same in both)."""
    env = {**os.environ, "PYTHONHASHSEED": "0"}
    extra = ["--toggle-collect=fmi2DoStep"] if toggle else []

    def count(k: int) -> int:
        return instructions.instructions(_probe_command(archive, master, k), extra, env)

    return (count(n) - count(0)) / n


def measure(archive: Path, master: str) -> MasterCost:
    """The counts and the CPU time of one archive in one master, n = its whole run."""
    a = open_archive(archive)
    n = round(a.stop_time / a.step)
    total = dostep = None
    if instructions.have_valgrind():
        total, dostep = _count(archive, master, n, False), _count(archive, master, n, True)
    cpu = min(_cpu_run(archive, master, n) for _ in range(3))
    return MasterCost(a.name, master, n, total, dostep, cpu / n * 1e6)


def _cpu_run(archive: Path, master: str, n: int) -> float:
    # a fresh process per run, as the counts: no state of an earlier master instance carries over
    code = f"from fmu.system.overhead import run_steps; print(run_steps({str(archive)!r}, {master!r}, {n}))"
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    return float(out.split()[-1])


def print_table(rows: list[MasterCost]) -> None:
    """The table and the target line (ECOS rows only: the target is ECOS's)."""
    if not instructions.have_valgrind():
        print(f"\ninstructions: {instructions.MISSING}")
    print(f"\nthe master's overhead: a closed-loop communication step against the two FMUs' own doSteps "
          f"(target in ECOS <= {TARGET_OVERHEAD}x)")  # fmt: skip
    print(f"{'system':<17}{'master':<10}{'steps':>6}{'instr/step':>12}{'doSteps':>9}{'ratio':>7}{'CPU us/step':>13}")
    for r in rows:
        total = "n/a" if r.total is None else f"{r.total:.0f}"
        dostep = "n/a" if r.dostep is None else f"{r.dostep:.0f}"
        ratio = "n/a" if r.ratio is None else f"{r.ratio:.2f}"
        print(f"{r.system:<17}{r.master:<10}{r.n:>6}{total:>12}{dostep:>9}{ratio:>7}{r.cpu_us:>13.1f}")
    print("instr/step: callgrind, all instructions of the process per communication step (a run of the whole system "
          "minus a run of 0 steps: set-up cancelled); doSteps: the instructions inside fmi2DoStep of both FMUs in the "
          "same kind of run (--toggle-collect=fmi2DoStep); ratio = instr/step / doSteps; CPU us/step: the master's "
          "steps in one call, CPU time of the process (all threads), best of 3, varies with the load; instr/step "
          "varies between runs too (the masters' threads waiting for work), doSteps does not")  # fmt: skip
    ecos = [r.ratio for r in rows if r.master == "ecos" and r.ratio is not None]
    if not ecos:
        print(f"target ECOS step / doSteps <= {TARGET_OVERHEAD}: not counted")
        return
    worst = max(ecos)
    verdict = "met" if worst <= TARGET_OVERHEAD else "NOT met"
    print(f"target ECOS step / doSteps <= {TARGET_OVERHEAD}, instructions: worst {worst:.2f}: {verdict}")


def main(build_dir: str = "build/bench", systems: tuple[str, ...] = SYSTEMS) -> int:
    """`rbfmu bench --master`: build the shipped systems' archives, count and time them in
    both masters, print the table. Returns the exit status."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in systems:
            archive = build_system(name, tmp, build_dir)
            for master in MASTER_RUNNERS:
                rows.append(measure(archive, master))
                r = rows[-1]
                print(f"{name} in {master}: {r.n} steps, ratio {'n/a' if r.ratio is None else f'{r.ratio:.2f}'}, "
                      f"{r.cpu_us:.1f} us CPU per step", flush=True)  # fmt: skip
    print_table(rows)
    return 0
