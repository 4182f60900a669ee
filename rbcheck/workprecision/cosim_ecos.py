"""Co-simulation with ECOS as the loop: the report's PD slew as the cosim_slew system against Exudyn chunk by chunk.

The system `cosim_slew` (fmu/system/systems/) wires torque_driven to the attitude_torque_pd
controller FMU (the law of rbcheck's AttitudePD in CasADi, T_s = Δ) and leaves the constant
world-frame disturbance on the plant's own tau_world input (its .ssv start value). ECOS steps
both FMUs Jacobi-style: it reads every output after the doSteps and then sets the inputs, so the
plant holds law(x_{k−1}) over [t_k, t_{k+1}] (law(x_0) at k = 0). The reference and Exudyn's
chunk-by-chunk loop therefore close the same delayed loop (rbcheck.baselines.rigid_body.
OneSampleDelay around the same AttitudePD): like for like.

Timed on the ECOS side: `EcosSimulation.step(n)`, one call for the n = T/Δ communication steps
(both FMUs' doSteps, ECOS's exchange of the 7 + 3 connected values, its TBB scheduling), wall
(perf_counter) and the process's CPU time (all threads); not timed: loading the archive,
unpacking the FMUs, instantiation, init, reading the end state. Exudyn: `simulate_scene`'s timed
solve, one SolveSteps per Δ with the Python controller between (as in the fmpy rows). The plant's
method is its default rk8 in every rung: ECOS skips Enumeration variables (`method`), so the
rungs set the Real parameters tolerance and h_max in the archive's .ssv.
"""

from __future__ import annotations

import dataclasses
import math
import statistics
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fmu.system.build import BuiltSystem, check_built, write_built
from fmu.system.masters import load_tbb
from modelsrc.scene import load_scene

from .config import Config
from .cosim import EXUDYN_COSIM, CosimRun, cosim_reference, exudyn_runs
from .harness import advance, show
from .references import Reference, errors

if TYPE_CHECKING:
    from tqdm import tqdm

SYSTEM = "cosim_slew"
PLANT = "plant"
# (label, plant parameters as functions of Δ): fixed rk8 steps, and rk8 under error control
ECOS_RUNGS: tuple[tuple[str, dict[str, float]], ...] = (
    ("rk8, fixed, h_max = Δ", {"tolerance": 0.0, "h_max": 1.0}),
    ("rk8, fixed, h_max = Δ/4", {"tolerance": 0.0, "h_max": 0.25}),
    ("rk8, error control, tol = 1e-10", {"tolerance": 1e-10}),
    ("rk8, error control, tol = 1e-6", {"tolerance": 1e-6}),
)


@dataclass
class EcosRun:
    """One rung of the ECOS loop: wall and CPU seconds of `step(n)` (median of 3), the error at T."""

    config: str
    wall: float
    cpu: float
    err: float
    e_w: float
    e_R: float


@dataclass
class EcosCosim:
    """The ECOS part: T, Δ (s), the delayed loop's reference, how far the delay-free loop ends
    from it (e), the ECOS rungs, Exudyn's delayed loops, and the target's smallest speed-up
    (wall and CPU) with its (ECOS, Exudyn) pair; `note` says why nothing was measured."""

    T: float
    dt: float
    ref: Reference | None = None
    delay_gap: float = float("nan")
    ecos: list[EcosRun] = dataclasses.field(default_factory=list)
    exudyn: list[CosimRun] = dataclasses.field(default_factory=list)
    min_speedup: float | None = None
    min_speedup_cpu: float | None = None
    min_pair: tuple[str, str] | None = None
    note: str = ""


def count_ecos_units() -> int:
    """Progress units of the ECOS part: build, reference, the ECOS rungs, Exudyn's runs."""
    return 2 + len(ECOS_RUNGS) + len(EXUDYN_COSIM)


def rung_archives(built: BuiltSystem, dt: float, out_dir: Path) -> list[tuple[str, Path]]:
    """One .ssp per rung of ECOS_RUNGS from the system built and checked once (`check_built`),
    its plant's tolerance and h_max (× Δ) replaced per rung."""
    plant = built.system.components[PLANT]
    out = []
    for i, (label, params) in enumerate(ECOS_RUNGS):
        values = {k: v * dt if k == "h_max" else v for k, v in params.items()}
        comp = dataclasses.replace(plant, parameters={**plant.parameters, **values})
        system = dataclasses.replace(built.system, components={**built.system.components, PLANT: comp})
        out.append((label, write_built(dataclasses.replace(built, system=system), out_dir / f"rung{i}")))
    return out


def ecos_loop(archive: Path, step: float, n: int) -> tuple[float, float, np.ndarray, np.ndarray]:
    """(wall s, CPU s, q(T), ω(T) rad/s body) of n communication steps of `step` (s) in ECOS,
    timed around the one `step(n)` call alone (module docstring)."""
    load_tbb()
    from ecospy.EcosSimulation import EcosSimulation

    sim = EcosSimulation(step, ssp_path=str(archive))
    try:
        if not sim.init(parameter_set="parameters"):
            raise RuntimeError(f"{archive}: ECOS could not initialise the system")
        cpu0, wall0 = time.process_time(), time.perf_counter()
        sim.step(n)
        wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
        q = np.array([sim.get_real(f"{PLANT}::q[{i}]") for i in (1, 2, 3, 4)])
        w = np.array([sim.get_real(f"{PLANT}::w_body[{i}]") for i in (1, 2, 3)])
        sim.terminate()
    finally:
        sim.free()
    return wall, cpu, q, w


def ecos_speedup(ecos: Sequence[EcosRun], exudyn: Sequence[CosimRun], ref: Reference) -> tuple[Any, Any, Any]:
    """For every Exudyn loop, the ECOS rungs at least as accurate (or within 3× the reference's
    own error); the smallest Exudyn/ECOS ratio of wall times (each Exudyn loop against the fastest
    such rung in wall time) and, separately, of CPU times (each process's CPU time over its timed
    loop; the machine's load inflates wall times, ECOS's waiting TBB worker its CPU time), and the
    (ECOS, Exudyn) pair of the smaller of the two."""
    walls: list[tuple[float, str, str]] = []
    cpus: list[tuple[float, str, str]] = []
    for ex in (r for r in exudyn if math.isfinite(r.total)):
        ok = [r for r in ecos if r.err <= max(ex.err, 3 * ref.floor)]
        if not ok:
            continue
        fw, fc = min(ok, key=lambda r: r.wall), min(ok, key=lambda r: r.cpu)
        walls.append((ex.total / fw.wall, fw.config, ex.config))
        cpus.append((ex.cpu / fc.cpu, fc.config, ex.config))
    if not walls:
        return None, None, None
    w, c = min(walls), min(cpus)
    worst = w if w[0] <= c[0] else c
    return w[0], c[0], (worst[1], worst[2])


def ecos_cosim(cfg: Config, build_dir: Path, progress: tqdm[Any] | None) -> EcosCosim:
    """The ECOS part (module docstring) at the report's T and Δ; Δ must be the system's step."""
    T, dt = cfg.cosim_T, cfg.cosim_dt
    res = EcosCosim(T, dt)
    show(progress, "co-simulation: ECOS system build")
    built = check_built(SYSTEM, build_dir)  # the FMI 2.0 FMUs in build_dir
    archives = rung_archives(built, dt, build_dir / "cosim_ecos")
    step = built.system.step
    advance(progress, "co-simulation: ECOS system build")
    if abs(step - dt) > 1e-12 * dt:
        res.note = f"not measured: the report's Δ = {dt:g} s is not the system {SYSTEM}'s step {step:g} s"
        return res
    sc = load_scene(cfg.cosim_scene)
    res.ref = ref = cosim_reference(sc, T, dt, delayed=True)
    free = cosim_reference(sc, T, dt)
    res.delay_gap = errors(free.w, free.q, ref)[2]
    advance(progress, "co-simulation: delayed reference")
    n = round(T / dt)
    for label, path in archives:
        show(progress, f"co-simulation: ECOS {label}")
        reps = [ecos_loop(path, dt, n) for _ in range(3)]
        e_w, e_R, e = errors(reps[0][3][None], reps[0][2][None], ref)
        wall, cpu = statistics.median(r[0] for r in reps), statistics.median(r[1] for r in reps)
        res.ecos.append(EcosRun(label, wall, cpu, e, e_w, e_R))
        advance(progress, f"co-simulation: ECOS {label}")
    res.exudyn = exudyn_runs(sc, T, dt, ref, progress, delayed=True)
    res.min_speedup, res.min_speedup_cpu, res.min_pair = ecos_speedup(res.ecos, res.exudyn, ref)
    return res


def target_row(res: EcosCosim, target: float) -> str:
    """The targets table's row of the ECOS loop (markdown)."""
    head = f"| co-simulation in ECOS at Δ = {res.dt:g} s: ≥ {target:.0f}× faster than Exudyn chunk by chunk | "
    if res.min_speedup is None:
        return head + f"not measured | {res.note or 'no ECOS rung as accurate as an Exudyn loop'} |"
    worst = min(res.min_speedup, res.min_speedup_cpu if res.min_speedup_cpu is not None else math.inf)
    status = "met" if worst >= target else "NOT met"
    pair = res.min_pair or ("-", "-")
    return (
        head + f"{status} | smallest speed-up {res.min_speedup:.1f}× in wall time, {_fmt(res.min_speedup_cpu)}× in "
        f"CPU time (the smaller: ECOS {pair[0]} vs Exudyn {pair[1]}; met only when both are), the same delayed loop "
        "both sides; ECOS `step(n)` alone against Exudyn's loop incl. its Python controller |"
    )


def _fmt(v: float | None, spec: str = ".1f") -> str:
    return "n/a" if v is None or not math.isfinite(v) else format(v, spec)


def ecos_markdown(res: EcosCosim) -> list[str]:
    """The report's subsection on the ECOS loop (lines of markdown)."""
    out = ["### The same loop in ECOS\n"]
    if res.ref is None:
        out.append(f"{res.note}\n")
        return out
    n = round(res.T / res.dt)
    out.append(
        f"The system `{SYSTEM}` (fmu/system/systems/): torque_driven's FMU and the controller FMU attitude_torque_pd "
        "(AttitudePD's body-torque law in CasADi, sampled every Δ; its outputs equal AttitudePD's to round-off, "
        "tests/fmi/test_controller_attitude_torque_pd.py), the 0.02 N·m disturbance on the plant's own unconnected "
        "tau_world (a start value in the .ssv), built to an .ssp (FMI 2.0) and run in ECOS (ecospy). ECOS steps "
        "Jacobi-style: the plant holds law(x_{k−1}) over [t_k, t_{k+1}] (law(x_0) at k = 0), one sample of delay. "
        f"So the reference here is that delayed loop ({res.ref.source}"
        + (f", own error estimate {res.ref.floor:.1e}" if res.ref.floor > 0 else ", bit-identical at rtol 3e-13")
        + f"; the delay-free loop of the table above ends e = {res.delay_gap:.1e} away from it), and Exudyn closes "
        "the same delayed loop chunk by chunk (`rbcheck.baselines.rigid_body.OneSampleDelay` around the same "
        "AttitudePD). ECOS timed: its `step(n)`, one call for the "
        f"{n} communication steps (both FMUs' doSteps and ECOS's exchange), wall and CPU time of the process (all "
        "threads), median of 3; loading, unpacking, init and reading the end state excluded. Exudyn timed: its "
        "stepping loop (one `SolveSteps` per Δ and the Python controller between), wall and CPU. The plant's "
        "method is rk8 in every rung (ECOS skips Enumeration variables); the rungs set tolerance and h_max.\n"
    )
    out.append(
        "| tool | configuration | wall (s) | CPU (s) | µs per Δ (wall) | µs per Δ (CPU) | e | e_ω (rad/s) | e_R (rad) |"
    )
    out.append("|---|---|---|---|---|---|---|---|---|")
    for r in res.ecos:
        out.append(
            f"| ECOS | {r.config} | {r.wall:.3g} | {r.cpu:.3g} | {r.wall / n * 1e6:.1f} | {r.cpu / n * 1e6:.1f} | "
            f"{r.err:.1e} | {r.e_w:.1e} | {r.e_R:.1e} |"
        )
    for x in res.exudyn:
        out.append(
            f"| Exudyn | {x.config} | {_fmt(x.total, '.3g')} | {_fmt(x.cpu, '.3g')} | {_fmt(x.total / n * 1e6)} | "
            f"{_fmt(x.cpu / n * 1e6)} | {_fmt(x.err, '.1e')} | {_fmt(x.e_w, '.1e')} | {_fmt(x.e_R, '.1e')} |"
        )
    if res.min_speedup is not None and res.min_pair:
        out.append(
            f"\nAt equal error (each Exudyn loop against the fastest ECOS rung at least as accurate, in wall time "
            f"and in CPU time separately) the smallest speed-up is {res.min_speedup:.1f}× in wall time and "
            f"{_fmt(res.min_speedup_cpu)}× in CPU time (the smaller of the two: ECOS {res.min_pair[0]} against "
            f"Exudyn {res.min_pair[1]}). Wall times carry the machine's load (Exudyn's wall here is "
            f"{_fmt(statistics.median(x.total / x.cpu for x in res.exudyn if x.cpu > 0))}× its CPU time), CPU times "
            "ECOS's TBB worker waiting for work; the ECOS rungs differ by the plant's work "
            "alone, one rk8 step per Δ (Δ/4: four), so their spread is mostly noise. Where an ECOS step's time "
            "goes: callgrind counts this system's step in ECOS at ~27 000 instructions, ~6 000 of them inside the "
            "two FMUs' fmi2DoStep, the rest ECOS's own exchange and scheduling (docs/user_guide.md, the master's "
            "overhead, `fmu.system.overhead.measure`; not re-counted here: ~7 min under callgrind).\n"
        )
    return out
