"""C-level timing of the FMU: the one module that times the generated step and fmi3DoStep in C.

Per scene: ns per internal step of the generated step function in a C loop, the same
through fmi3DoStep (one long step, the layer's own overhead included; or doSteps of 1 and
10 internal steps called from a C loop: `run_loops`), and µs per doStep + getFloat64 of
all outputs through fmpy at the scene's communication step (`fmpy_step_us`).
`c_step_ns_all` extends the C timing to every method of an FMU, and `fmu_compute_ctypes`
times fmi3DoStep called from a raw ctypes loop (no fmpy layer); the work-precision report
(rbcheck.workprecision) takes its C timings from here. `work_limit_walls` times the
longest doStep the default work_limit admits, per method (docs/robustness.md §1).
Times are CPU time of the process (fmu/c/bench_step.c), from one run on this machine;
compare them as ratios. `rbfmu bench` (fmu.bench.steps) puts them beside instruction counts
and the hand-written reference.
"""

from __future__ import annotations

import ctypes
import subprocess
import tempfile
import time
import zipfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from modelsrc.methods import METHODS, WORK_LIMIT, rotation_limit
from modelsrc.scene import Scene, fixed_step

from ..build.compile import CFLAGS, BuildError, compile_units
from ..drive.instance import FmuError, FmuInstance

HARNESS = Path(__file__).resolve().parent.parent / "c" / "bench_step.c"
# Methods whose step costs ~0.1 µs (explicit, no Newton iteration, no elliptic functions);
# the others cost µs per step and are timed over fewer steps.
CHEAP_METHODS = ("rk4", "rk8", "splitting")


def compile_harness(fmu: Path, tmp: Path) -> Path:
    """Extract the FMU's sources into `tmp` and compile the harness fmu/c/bench_step.c
    against the objects of its FMI 3.0 binary, compiled with the binary's own flags (from the
    object cache when the FMU's host binary was built on this machine: fmu.build.compile.compile_units);
    returns the executable."""
    with zipfile.ZipFile(fmu) as z:
        z.extractall(tmp)
    src = tmp / "sources"
    exe = tmp / "bench"
    try:
        objs, _ = compile_units(src, tmp, 3, [])
    except BuildError as exc:
        raise RuntimeError(f"benchmark harness failed to compile:\n{exc}") from exc
    cmd = ["gcc", *CFLAGS, "-I", str(src), str(HARNESS), *map(str, objs), "-o", str(exe), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"benchmark harness failed to compile:\n{proc.stderr}")
    return exe


def harness_args(exe: Path, mode: str, n: int, method_value: int | None, h: float) -> list[str]:
    """The harness's command line for `mode` (fmu/c/bench_step.c: time, loops, raw, long,
    loop1, loop10) over n fixed steps of h (s) (rounded up to even: the raw loop ping-pongs
    two steps per iteration) of the method with enumeration value `method_value` (the
    modelDescription's; None: the FMU's first method)."""
    n += n % 2
    value = "0" if method_value is None else str(int(method_value))  # 0: the first method
    return [str(exe), mode, str(n), value, repr(float(h))]


def _run_harness(exe: Path, n: int, method_value: int | None, h: float) -> tuple[float, float]:
    """(raw generated step, step through one long fmi3DoStep) in ns of CPU time per internal
    step, best of 5 inside the harness, over n fixed steps of h (s) (`harness_args`)."""
    args = harness_args(exe, "time", n, method_value, h)
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1])


def run_loops(exe: Path, n: int, method_value: int | None, h: float) -> tuple[float, float, float, float]:
    """ns of CPU time, best of 5 inside one harness process: per raw generated step, per
    internal step of one long fmi3DoStep (n steps each), per fmi3DoStep of 1 internal step
    and per fmi3DoStep of 10 internal steps, called from a C loop over n/4 internal steps."""
    args = harness_args(exe, "loops", n, method_value, h)
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1]), float(out[2]), float(out[3])


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
        return _run_harness(compile_harness(fmu, Path(tmp)), n, method_value, default_step(fmu))


def _harness_state(
    exe: Path, n: int, method_value: int | None, h: float, x0: Sequence[float] | None, u: Sequence[float] | None
) -> np.ndarray:
    """The state after n raw generated steps of h (s) of one method from x0 (the FMU's
    start values if None) with the inputs u held (the FMU's input start values if None)."""
    args = harness_args(exe, "raw", n, method_value, h)
    if x0 is not None and u is not None:
        args += [repr(float(v)) for v in (*x0, *u)]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return np.array([float(v) for v in out])


def c_cosim(
    exe: Path,
    n: int,
    method_value: int,
    H: float,
    tolerance: float,
    h_max: float,
    x0: Sequence[float],
    u: Sequence[float],
    repeats: int = 3,
) -> tuple[float, int, np.ndarray]:
    """A C master's run of the harness `exe` (`compile_harness`): n doSteps of H (s) from the
    state x0 with the inputs u held (both in the FMU's order), the method's enumeration value,
    tolerance and h_max (s) as given. Returns (CPU seconds of the doSteps, best of `repeats`;
    the internal steps they took; the final state)."""
    args = [str(exe), "cosim", str(n), str(int(method_value)), repr(float(H)), repr(float(tolerance))]
    args += [repr(float(h_max)), str(repeats), *(repr(float(v)) for v in (*x0, *u))]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), int(float(out[1])), np.array([float(v) for v in out[2:]])


def generated_state(
    fmu: Path, n: int, method: str, x0: Sequence[float] | None = None, u: Sequence[float] | None = None
) -> np.ndarray:
    """The state after n generated fixed steps of `method` ("rk4", "rk8") of `default_step`
    from x0 with the inputs u held (both in the FMU's order; None: its start values): what
    `reference_state` must reproduce."""
    return generated_states(fmu, n, (method,), x0, u)[method]


def generated_states(
    fmu: Path,
    n: int,
    methods: Sequence[str],
    x0: Sequence[float] | None = None,
    u: Sequence[float] | None = None,
) -> dict[str, np.ndarray]:
    """method -> `generated_state` of each method, from one compile of the harness (the
    compile of the FMU's generated C, seconds, is most of the cost)."""
    with tempfile.TemporaryDirectory() as tmp:
        exe = compile_harness(fmu, Path(tmp))
        h = default_step(fmu)
        return {m: _harness_state(exe, n, METHODS[m].value, h, x0, u) for m in methods}


def c_step_ns_all(fmu: Path, n_explicit: int, n_implicit: int) -> dict[str, tuple[float, float]]:
    """method -> (raw generated step, through fmi3DoStep) in ns per internal step, for
    every method of the FMU: the harness compiled once and run per method with the
    enumeration value read from the modelDescription (`FmuInstance.method_values`),
    n_explicit steps for CHEAP_METHODS and n_implicit for the others."""
    with FmuInstance(fmu) as inst:
        methods = inst.method_values
    out: dict[str, tuple[float, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        exe = compile_harness(fmu, Path(tmp))
        h = default_step(fmu)
        for name, value in methods.items():
            out[name] = _run_harness(exe, n_explicit if name in CHEAP_METHODS else n_implicit, value, h)
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
