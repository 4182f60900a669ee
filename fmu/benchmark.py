"""C-level timing of the FMU: the one module that times the generated step and fmi3DoStep in C.

Per scene: ns per internal step of the generated step function in a C loop, the same
through fmi3DoStep (one long step, the layer's own overhead included), and µs per
doStep + getFloat64 of all outputs through fmpy at the scene's communication step.
`c_step_ns_all` extends the C timing to every method of an FMU, and `fmu_compute_ctypes`
times fmi3DoStep called from a raw ctypes loop (no fmpy layer); the work-precision report
(rbcheck.workprecision) takes its C timings from here. `work_limit_walls` times the
longest doStep the default work_limit admits, per method (docs/robustness.md §1).
Timings are from one run on this machine; compare them as ratios. `rbfmu bench` times the
generated step and the C reference in separate processes, alternately (A B A B ...), and
reports the spread of their ratio over the pairs, so that one badly placed process cannot
decide the "raw/ref <= 1.2" row (`interleaved_step_ns`).
"""

from __future__ import annotations

import ctypes
import dataclasses
import shutil
import subprocess
import tempfile
import time
import zipfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from modelsrc.methods import METHODS, WORK_LIMIT, rotation_limit
from modelsrc.scene import Scene, fixed_step, list_scenes, load_scene

from .build_fmu import CFLAGS, GENERATED_EXTRA, build_fmu, c_sources
from .run import FmuError, FmuInstance

HARNESS = Path(__file__).resolve().parent / "c" / "bench_step.c"
REFERENCE = Path(__file__).resolve().parent / "c" / "bench_reference.c"
TARGET_REF_RATIO = 1.2  # the generated fixed RK4 step against the minimal hand-written C RK4
TARGET_NS = 150.0  # docs/report/report.md targets: <= 150 ns per RK4 internal step of the 7-state body
# Methods whose step costs ~0.1 µs (explicit, no Newton iteration, no elliptic functions);
# the others cost µs per step and are timed over fewer steps.
CHEAP_METHODS = ("rk4", "rk8", "splitting")
# The work-limit table: the cheapest right-hand side among the shipped scenes and the
# dearest (gravity), so that the wall time at the limit is bracketed.
WORK_LIMIT_SCENES = ("free_asymmetric", "heavy_top")
# `rbfmu bench`: pairs of processes (generated step, C reference), run alternately, and the
# steps each times (best of the harnesses' 5 repeats inside each process)
BENCH_PAIRS = 7
BENCH_STEPS = 1_000_000


def _compile_harness(fmu: Path, tmp: Path) -> Path:
    """Extract the FMU's sources into `tmp` and compile the harness fmu/c/bench_step.c
    against the C sources of its FMI 3.0 binary (build_fmu.c_sources); returns the executable."""
    with zipfile.ZipFile(fmu) as z:
        z.extractall(tmp)
    src = tmp / "sources"
    exe = tmp / "bench"
    sources = [str(src / f) for f in c_sources(3)]
    cmd = [
        "gcc",
        *[f for f in CFLAGS if f != "-fPIC"],
        *GENERATED_EXTRA,
        "-I",
        str(src),
        str(HARNESS),
        *sources,
        "-o",
        str(exe),
        "-lm",
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"benchmark harness failed to compile:\n{proc.stderr}")
    return exe


def _run_harness(exe: Path, n: int, method_value: int | None, h: float) -> tuple[float, float, float]:
    """(raw generated step, step through fmi3DoStep) in ns per internal step, best of 5
    inside the harness, over n fixed steps of h (s) (rounded up to even: the harness
    ping-pongs two steps per iteration) of the method with enumeration value
    `method_value` (the modelDescription's; None: the FMU's first method); and the last
    state component after the n raw steps."""
    n += n % 2
    value = "0" if method_value is None else str(int(method_value))  # 0: the first method
    args = [str(exe), str(n), value, repr(float(h))]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1]), float(out[2])


def default_step(fmu: Path) -> float:
    """The internal step (s) the benchmark times an FMU at: its scene's fixed step (the
    start value of h_max, else a tenth of the default communication step: Scene.fixed_step)."""
    md = read_model_description(str(fmu))
    h_max = next(float(v.start) for v in md.modelVariables if v.name == "h_max")
    return fixed_step(h_max, float(md.defaultExperiment.stepSize))


def c_step_ns(fmu: Path, n: int = 4_000_000, method_value: int | None = None) -> tuple[float, float]:
    """(raw generated step, step through fmi3DoStep) in ns per internal step of one method
    (enumeration value; None: the FMU's first method, rk4 in the shipped scenes), fixed
    steps of `default_step`."""
    with tempfile.TemporaryDirectory() as tmp:
        return _run_harness(_compile_harness(fmu, Path(tmp)), n, method_value, default_step(fmu))[:2]


def generated_rk4_last_state(fmu: Path, n: int) -> float:
    """The last state component after n generated RK4 steps of `default_step` from the
    FMU's start values (its first method must be rk4): what `reference_last_state` must
    reproduce."""
    with tempfile.TemporaryDirectory() as tmp:
        return _run_harness(_compile_harness(fmu, Path(tmp)), n, None, default_step(fmu))[2]


def reference_features(scene: Scene) -> tuple[list[str], np.ndarray]:
    """The C macros that select the scene's equations in fmu/c/bench_reference.c, and the
    inertia about the point the body turns about (kg·m², body): about the centre of mass,
    shifted to a pivot by the parallel-axis theorem (docs/theory.md §3.2)."""
    if scene.rotors:
        raise ValueError(
            f"scene {scene.name}: fmu/c/bench_reference.c has no rotors (the gyrostat's reference kernel is "
            "not written yet); `rbfmu bench` leaves rotor scenes out"
        )
    if scene.has("orbit") or scene.has("central_gravity"):
        raise ValueError(
            f"scene {scene.name}: fmu/c/bench_reference.c has no orbit (gravity gradient); `rbfmu bench` leaves "
            "orbit and central-field scenes out"
        )
    I = np.asarray(scene.inertia, dtype=float)
    flags = []
    if scene.has("gravity") and not scene.has("translation"):
        r = np.asarray(scene.r_cm, dtype=float)
        I = I + scene.mass * (float(r @ r) * np.eye(3) - np.outer(r, r))
        if scene.pivot_inertia is not None:  # given about the pivot: as given
            I = np.asarray(scene.pivot_inertia, dtype=float)
        flags.append("REF_GRAVITY")
    if np.any(I[~np.eye(3, dtype=bool)] != 0.0):
        flags.append("REF_FULL_INERTIA")
    names = {"friction": "REF_FRICTION", "torque_body": "REF_TAU_BODY", "torque_world": "REF_TAU_WORLD",
             "prescribed_rate": "REF_PRESCRIBED", "translation": "REF_TRANSLATION", "moving_pivot": "REF_MOVING_PIVOT",
             "force_body": "REF_FORCE_BODY", "force_world": "REF_FORCE_WORLD"}  # fmt: skip
    flags += [macro for feature, macro in names.items() if scene.has(feature)]
    if scene.has("translation") and scene.has("gravity"):
        flags.append("REF_FREE_GRAVITY")
    points = list(scene.force_points.values())
    if points:
        world = sum(1 << k for k, fp in enumerate(points) if fp.frame == "world")
        flags += [f"REF_NPOINTS={len(points)}", f"REF_POINT_WORLD={world}"]
    return flags, I


def _compile_reference(scene: Scene, tmp: Path) -> list[str]:
    """Compile fmu/c/bench_reference.c for the scene's equations into `tmp`; returns its
    command line but the step count: [exe, h, start state, parameters] at the scene's h_max,
    start state and input start values (the FMU's start values)."""
    flags, I = reference_features(scene)
    state = [*scene.q0, *scene.w0] + ([*scene.x0, *scene.v0] if scene.moves else [])
    params = [*I.ravel(), *np.linalg.inv(I).ravel(), scene.mass, *scene.r_cm, *scene.g, scene.c_friction]
    for name in ("tau_body", "tau_world", "f_body", "f_world", "a_pivot"):
        params += list(scene.input_start(name))
    for name, fp in scene.force_points.items():
        params += [*fp.point, *scene.input_start(f"f_{name}")]
    exe = tmp / "reference"
    cmd = ["gcc", *[f for f in CFLAGS if f != "-fPIC"], "-Werror", *(f"-D{f}" for f in flags), str(REFERENCE),
           "-o", str(exe), "-lm"]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"the C reference failed to compile for {scene.name}:\n{proc.stderr}")
    return [str(exe), repr(float(scene.fixed_step)), *(repr(float(v)) for v in state + params)]


def _run_reference(cmd: list[str], n: int) -> tuple[float, float]:
    """(ns per step, best of 5 inside the process; last state component) of n reference steps."""
    out = subprocess.run([cmd[0], str(n), *cmd[1:]], check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1])


def _reference_run(scene: Scene, n: int) -> tuple[float, float]:
    """(ns per step, last state component after n steps) of the reference RK4 at the
    scene's h_max, start state and input start values (the FMU's start values)."""
    with tempfile.TemporaryDirectory() as tmp:
        return _run_reference(_compile_reference(scene, Path(tmp)), n)


def reference_step_ns(scene: Scene, n: int = 4_000_000) -> float:
    """ns per RK4 step of the minimal hand-written C reference of the scene's equations
    (fmu/c/bench_reference.c, never part of an FMU), best of 5."""
    return _reference_run(scene, n)[0]


def reference_last_state(scene: Scene, n: int) -> float:
    """The last state component after n reference RK4 steps (see generated_rk4_last_state)."""
    return _reference_run(scene, n)[1]


def c_step_ns_all(fmu: Path, n_explicit: int, n_implicit: int) -> dict[str, tuple[float, float]]:
    """method -> (raw generated step, through fmi3DoStep) in ns per internal step, for
    every method of the FMU: the harness compiled once and run per method with the
    enumeration value read from the modelDescription (`FmuInstance.method_values`),
    n_explicit steps for CHEAP_METHODS and n_implicit for the others."""
    with FmuInstance(fmu) as inst:
        methods = inst.method_values
    out: dict[str, tuple[float, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        exe = _compile_harness(fmu, Path(tmp))
        h = default_step(fmu)
        for name, value in methods.items():
            out[name] = _run_harness(exe, n_explicit if name in CHEAP_METHODS else n_implicit, value, h)[:2]
    return out


def fmu_compute_ctypes(inst: FmuInstance, dt: float, n: int, what: str = "") -> float:
    """Seconds spent in fmi3DoStep alone for n communication steps of dt (s) from t = 0:
    the raw ctypes function of the FMU's library called in a loop (no fmpy wrapper, no
    get/set; the inputs stay at their current values). The caller initialises `inst`
    (method, h_max, start and stop time); `what` names the run in the error message."""
    f = inst.c_function("fmi3DoStep")
    f.argtypes = [
        ctypes.c_void_p,
        ctypes.c_double,
        ctypes.c_double,
        ctypes.c_bool,
        ctypes.POINTER(ctypes.c_bool),
        ctypes.POINTER(ctypes.c_bool),
        ctypes.POINTER(ctypes.c_bool),
        ctypes.POINTER(ctypes.c_double),
    ]
    f.restype = ctypes.c_int
    b1, b2, b3, last = ctypes.c_bool(), ctypes.c_bool(), ctypes.c_bool(), ctypes.c_double()
    p1, p2, p3, pl = ctypes.byref(b1), ctypes.byref(b2), ctypes.byref(b3), ctypes.byref(last)
    comp = inst.c_instance
    tic = time.perf_counter()
    for k in range(n):
        if f(comp, k * dt, dt, False, p1, p2, p3, pl) != 0:
            raise RuntimeError(f"fmi3DoStep failed at t = {k * dt} s in the ctypes loop{f' ({what})' if what else ''}")
    return time.perf_counter() - tic


def _timed_step(fmu: Path, method_value: int, h: float, n: int, spin: float) -> tuple[bool, float]:
    """(accepted, s) of one doStep of n internal steps of h (s) from the start, the body
    tumbling at `spin` rad/s about (0.6, 0, 0.8)."""
    with FmuInstance(fmu) as inst:
        inst.set(
            # fixed steps (tolerance 0): an error-controlled doStep is charged the same cost
            # per attempt, so the fixed one at the limit bounds both (docs/robustness.md)
            {
                "method": method_value,
                "tolerance": 0.0,
                "h_max": h,
                "w_body[1]": 0.6 * spin,
                "w_body[2]": 0.0,
                "w_body[3]": 0.8 * spin,
            }
        )
        inst.initialize(0.0)
        tic = time.perf_counter()
        try:
            inst.step(0.0, n * h)
        except FmuError:
            return False, time.perf_counter() - tic
        return True, time.perf_counter() - tic


def work_limit_walls(fmu: Path, scene: Scene, spin: float = 100.0) -> dict[str, tuple[int, float, float]]:
    """method -> (internal steps, s of the longest doStep the default work_limit admits, s
    to refuse one internal step more) for the FMU of `scene`, the body tumbling at `spin`
    rad/s. The steps are the largest the layer takes: h|w| at 99 % of the method's rotation
    limit (where Newton iterates most), halved until the stability limit no longer adds
    steps, which the limit would refuse (a refusal costs microseconds)."""
    with FmuInstance(fmu) as inst:
        methods = inst.method_values
    out: dict[str, tuple[int, float, float]] = {}
    for name, value in methods.items():
        steps = int(WORK_LIMIT // METHODS[name].cost)  # one more exceeds the limit
        theta = rotation_limit(name, scene.torque_free)
        h = 0.99 * (theta if np.isfinite(theta) else 0.25) / spin
        for _ in range(30):
            accepted, wall = _timed_step(fmu, value, h, steps, spin)
            if accepted:
                break
            h /= 2
        else:
            raise RuntimeError(f"{name}: no step size gives a doStep of {steps} internal steps")
        accepted, refusal = _timed_step(fmu, value, h, steps + 1, spin)
        if accepted:
            raise RuntimeError(f"{name}: a doStep of {steps + 1} internal steps exceeds work_limit but ran")
        out[name] = (steps, wall, refusal)
    return out


@dataclasses.dataclass(frozen=True)
class Interleaved:
    """ns per internal step from processes run alternately: raw[k] (generated step in a C
    loop) and fmi[k] (through fmi3DoStep) from the k-th harness process, ref[k] from the
    k-th reference process, which ran right after it."""

    raw: tuple[float, ...]
    fmi: tuple[float, ...]
    ref: tuple[float, ...]

    def ratio_spread(self) -> tuple[float, float, float]:
        """(min, median, max) over the pairs of raw[k] / ref[k]."""
        r = np.asarray(self.raw) / np.asarray(self.ref)
        return float(r.min()), float(np.median(r)), float(r.max())

    def median(self, which: str) -> float:
        """Median ns per step of `which`: "raw", "fmi" or "ref"."""
        return float(np.median(getattr(self, which)))


def interleaved_step_ns(fmu: Path, scene: Scene, pairs: int = BENCH_PAIRS, n: int = BENCH_STEPS) -> Interleaved:
    """The FMU's first method (rk4 in the shipped scenes) at `default_step` and the C
    reference of the scene's equations, each timed in `pairs` processes of n steps, run
    alternately (harness, reference, harness, ...): a slow spell of the machine then
    lands on both sides of a few pairs instead of deciding the ratio."""
    raw, fmi, ref = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        exe = _compile_harness(fmu, Path(tmp))
        ref_cmd = _compile_reference(scene, Path(tmp))
        h = default_step(fmu)
        for _ in range(pairs):
            r, f, _last = _run_harness(exe, n, None, h)
            raw.append(r)
            fmi.append(f)
            ref.append(_run_reference(ref_cmd, n)[0])
    return Interleaved(tuple(raw), tuple(fmi), tuple(ref))


def fmpy_step_us(fmu: Path, h: float, h_fixed: float, n: int = 20000) -> float:
    """Median over 5 repeats of µs per doStep(h) + getFloat64(all outputs) through fmpy,
    with fixed RK4 internal steps of h_fixed (s), the work the other columns time."""
    with FmuInstance(fmu) as inst:
        outs = [v.valueReference for v in inst.md.modelVariables if v.causality == "output"]
        inst.set({"method": METHODS["rk4"].value, "tolerance": 0.0, "h_max": h_fixed})
        inst.initialize()
        t, times = 0.0, []
        for _ in range(5):
            t0 = time.perf_counter()
            for _ in range(n):
                inst.step(t, h)
                inst.get_float64(outs)
                t += h
            times.append((time.perf_counter() - t0) / n)
    return float(np.median(times)) * 1e6


def main(out_dir: str = "build/bench", scenes: Sequence[str] | None = None, work_limit: bool = True) -> int:
    """`rbfmu bench`: the table of every shipped scene (or `scenes`) and, with `work_limit`,
    the work-limit table. Returns the exit status."""
    out = Path(out_dir)
    if shutil.which("gcc") is None:
        print("gcc is needed for the benchmark")
        return 1
    rows, nxs = [], []
    for name in scenes or list_scenes():
        if load_scene(name).rotors:  # no reference kernel for the gyrostat yet (reference_features)
            print(f"{name}: left out: the C reference has no rotors yet")
            continue
        if load_scene(name).features & {"orbit", "central_gravity"}:  # nor an orbit (reference_features)
            print(f"{name}: left out: the C reference has no orbit")
            continue
        # inputs at zero: a step costs the same for any input value, and a thrust or torque
        # held over the 4e6 benchmark steps would spin the body up until the sub-step
        # limits refuse the step
        sc = dataclasses.replace(load_scene(name), inputs={})
        fmu = build_fmu(sc, out)
        iv = interleaved_step_ns(fmu, sc)
        raw, fmi, ref = iv.median("raw"), iv.median("fmi"), iv.median("ref")
        lo, mid, hi = iv.ratio_spread()
        sub = max(1, int(np.ceil(sc.step / sc.fixed_step - 1e-9)))
        us = fmpy_step_us(fmu, sc.step, sc.fixed_step)
        rows.append((name, raw, fmi, fmi / raw, sub, us, us * 1e3 / sub, ref, mid, lo, hi))
        nxs.append(13 if sc.moves else 7)
    print(
        f"{'scene':<20}{'raw C ns/step':>14}{'C ref ns':>9}{'raw/ref':>8}{'min..max':>12}{'FMI ns/step':>12}"
        f"{'FMI/raw':>9}{'substeps':>9}{'fmpy us/doStep':>15}{'fmpy ns/substep':>16}"
    )
    for r in rows:
        spread = f"{r[9]:.2f}..{r[10]:.2f}"
        print(
            f"{r[0]:<20}{r[1]:14.1f}{r[7]:9.1f}{r[8]:8.2f}{spread:>12}{r[2]:12.1f}{r[3]:9.3f}{r[4]:9d}{r[5]:15.2f}"
            f"{r[6]:16.1f}"
        )
    print(
        "raw: the generated RK4 step of fixed stepping (no error estimate) in a C loop; C ref: a minimal "
        "hand-written C RK4 of the same equations (fmu/c/bench_reference.c, benchmark only); fmpy: fixed RK4 steps"
    )
    print(
        f"ns/step: medians over {BENCH_PAIRS} processes each of the harness and the reference, run alternately "
        f"(best of 5 repeats of {BENCH_STEPS:,} steps inside each); raw/ref: median, min..max over the pairs"
    )
    # the target is for the 7-state body; a free body or a moving pivot has 13 states
    worst = max(r[2] for r, nx in zip(rows, nxs) if nx == 7)
    print(
        f"\ntarget <= {TARGET_NS:.0f} ns per RK4 internal step of the 7-state body: worst scene {worst:.1f} ns "
        f"({'met' if worst <= TARGET_NS else 'NOT met'})"
    )
    worst_row = max(rows, key=lambda r: r[8])
    name, ratio = worst_row[0], worst_row[8]
    print(
        f"target raw/ref <= {TARGET_REF_RATIO}: worst scene {name} {ratio:.2f} (median; pairs "
        f"{worst_row[9]:.2f}..{worst_row[10]:.2f}) ({'met' if ratio <= TARGET_REF_RATIO else 'NOT met'}; "
        "timings on one machine, compare ratios)"
    )
    if not work_limit:
        return 0
    print(f"\nthe longest doStep the default work_limit ({WORK_LIMIT:g} right-hand-side evaluations) admits:")
    print(f"{'scene':<16}{'method':<19}{'cost':>6}{'internal steps':>16}{'doStep s':>10}{'refusal us':>12}")
    for name in WORK_LIMIT_SCENES:
        sc = load_scene(name)
        for method, (steps, wall, refuse) in work_limit_walls(build_fmu(sc, out), sc).items():
            print(f"{name:<16}{method:<19}{METHODS[method].cost:>6g}{steps:>16,}{wall:>10.2f}{refuse * 1e6:>12.0f}")
    return 0
