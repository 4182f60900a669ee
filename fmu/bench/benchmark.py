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

from ..build.build_fmu import CFLAGS, GENERATED_EXTRA, build_fmu, c_sources
from ..drive.instance import FmuError, FmuInstance

HARNESS = Path(__file__).resolve().parent.parent / "c" / "bench_step.c"
REFERENCE = Path(__file__).resolve().parent.parent / "c" / "bench_reference.c"
TARGET_REF_RATIO = 1.2  # the generated fixed RK4 and RK8 steps against the minimal hand-written C kernels
# the methods fmu/c/bench_reference.c has: the FMU's fixed rk4 and rk8 (DOP853) steps
REFERENCE_METHODS = ("rk4", "rk8")
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


def _run_harness(exe: Path, n: int, method_value: int | None, h: float) -> tuple[float, float]:
    """(raw generated step, step through fmi3DoStep) in ns per internal step, best of 5
    inside the harness, over n fixed steps of h (s) (rounded up to even: the harness
    ping-pongs two steps per iteration) of the method with enumeration value
    `method_value` (the modelDescription's; None: the FMU's first method)."""
    n += n % 2
    value = "0" if method_value is None else str(int(method_value))  # 0: the first method
    args = [str(exe), str(n), value, repr(float(h))]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1])


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
        return _run_harness(_compile_harness(fmu, Path(tmp)), n, method_value, default_step(fmu))


def _harness_state(
    exe: Path, n: int, method_value: int | None, h: float, x0: Sequence[float] | None, u: Sequence[float] | None
) -> np.ndarray:
    """The state after n raw generated steps of h (s) of one method from x0 (the FMU's
    start values if None) with the inputs u held (the FMU's input start values if None)."""
    n += n % 2
    value = "0" if method_value is None else str(int(method_value))
    args = [str(exe), str(n), value, repr(float(h))]
    if x0 is not None and u is not None:
        args += [repr(float(v)) for v in (*x0, *u)]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout.split()
    return np.array([float(v) for v in out[2:]])


def generated_state(
    fmu: Path, n: int, method: str, x0: Sequence[float] | None = None, u: Sequence[float] | None = None
) -> np.ndarray:
    """The state after n generated fixed steps of `method` ("rk4", "rk8") of `default_step`
    from x0 with the inputs u held (both in the FMU's order; None: its start values): what
    `reference_state` must reproduce."""
    value = METHODS[method].value
    with tempfile.TemporaryDirectory() as tmp:
        return _harness_state(_compile_harness(fmu, Path(tmp)), n, value, default_step(fmu), x0, u)


def _rotation_inertia(scene: Scene) -> np.ndarray:
    """The inertia about the point the body turns about (kg·m², body): about the centre of
    mass, shifted to a fixed or moving pivot by the parallel-axis theorem (docs/theory.md
    §3.2), or as given about the pivot."""
    I = np.asarray(scene.inertia, dtype=float)
    if scene.has("gravity") and not scene.has("translation"):
        if scene.pivot_inertia is not None:
            return np.asarray(scene.pivot_inertia, dtype=float)
        r = np.asarray(scene.r_cm, dtype=float)
        I = I + scene.mass * (float(r @ r) * np.eye(3) - np.outer(r, r))
    return I


def _rotor_axis(scene: Scene, name: str) -> int:
    """The body axis (0, 1, 2) a rotor spins about; the reference kernel has rotors on body
    axes only (every shipped scene's)."""
    axis = np.asarray(scene.rotors[name].axis, dtype=float)
    hits = [k for k in range(3) if axis[k] == 1.0 and np.count_nonzero(axis) == 1]
    if not hits:
        raise ValueError(
            f"scene {scene.name}: rotor {name} has the axis {list(axis)}; the C reference "
            "(fmu/c/bench_reference.c) takes rotors along a positive body axis only"
        )
    return hits[0]


def _torque_and_speed_rotors(scene: Scene) -> tuple[list[str], list[str]]:
    names = list(scene.rotors)
    return [n for n in names if not scene.rotors[n].speed], [n for n in names if scene.rotors[n].speed]


def _mass_matrix(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """(I about the rotation point, M = I − Σ_torque-mode J g gᵀ) (docs/theory.md §8.1, §8.5)."""
    I = _rotation_inertia(scene)
    M = I.copy()
    for name in _torque_and_speed_rotors(scene)[0]:
        g = np.asarray(scene.rotors[name].axis, dtype=float)
        M = M - scene.rotors[name].J * np.outer(g, g)
    return I, M


def reference_features(scene: Scene) -> list[str]:
    """The C macros that select the scene's equations in fmu/c/bench_reference.c."""
    if scene.has("central_gravity"):
        raise ValueError(
            f"scene {scene.name}: fmu/c/bench_reference.c has no central field (docs/theory.md §9.7); "
            "`rbfmu bench` leaves such scenes out"
        )
    I, M = _mass_matrix(scene)
    flags = []
    off = ~np.eye(3, dtype=bool)
    if np.any(I[off] != 0.0) or np.any(M[off] != 0.0):
        flags.append("REF_FULL_INERTIA")
    if scene.has("gravity") and not scene.has("translation"):
        flags.append("REF_GRAVITY")
    names = {"friction": "REF_FRICTION", "torque_body": "REF_TAU_BODY", "torque_world": "REF_TAU_WORLD",
             "prescribed_rate": "REF_PRESCRIBED", "translation": "REF_TRANSLATION", "moving_pivot": "REF_MOVING_PIVOT",
             "force_body": "REF_FORCE_BODY", "force_world": "REF_FORCE_WORLD", "orbit": "REF_ORBIT",
             "gravity_gradient": "REF_GRAVITY_GRADIENT"}  # fmt: skip
    flags += [macro for feature, macro in names.items() if scene.has(feature)]
    if scene.has("translation") and scene.has("gravity"):
        flags.append("REF_FREE_GRAVITY")
    points = list(scene.force_points.values())
    if points:
        world = sum(1 << k for k, fp in enumerate(points) if fp.frame == "world")
        flags += [f"REF_NPOINTS={len(points)}", f"REF_POINT_WORLD={world}"]
    torque, speed = _torque_and_speed_rotors(scene)
    if torque:
        flags += [f"REF_NTROT={len(torque)}", "REF_TAX=" + ",".join(str(_rotor_axis(scene, n)) for n in torque)]
    if speed:
        flags += [f"REF_NSROT={len(speed)}", "REF_SAX=" + ",".join(str(_rotor_axis(scene, n)) for n in speed)]
        props = {scene.rotors[n].propeller for n in speed}
        if props == {True}:
            flags.append("REF_PROPELLERS")
            body_forces = scene.has("force_body") or any(fp.frame == "body" for fp in scene.force_points.values())
            if not body_forces:  # the thrusts along the rotor axes only: R times those columns
                flags.append(f"REF_FB_AXES={sum({1 << _rotor_axis(scene, n) for n in speed})}")
        elif props != {False}:
            raise ValueError(f"scene {scene.name}: the C reference takes speed-mode rotors all propellers or none")
    return flags


def reference_parameters(scene: Scene) -> list[float]:
    """What the reference kernel reads as parameters, computed once from the scene's
    (fmu/c/bench_reference.c, Params, read_params): I about the rotation point, M⁻¹ (the
    inverse of I − Σ J g gᵀ, I⁻¹ without rotors), Euler's coefficients (I_2 − I_3) M⁻¹_1
    (cyclic), c M⁻¹ (diagonal; c for a full tensor), the weight m g, m, r_cm, g, 1/m, the
    gravity gradient's 3 n² (I_3 − I_2) M⁻¹_1 (cyclic; 3 n² I for a full tensor), n, the
    force points, the rotors' J and 1/J, the propellers' k_f, k_m and positions."""
    I, M = _mass_matrix(scene)
    Minv = np.linalg.inv(M)
    full = "REF_FULL_INERTIA" in reference_features(scene)
    d = np.diag(Minv)
    eul = [(I[1, 1] - I[2, 2]) * d[0], (I[2, 2] - I[0, 0]) * d[1], (I[0, 0] - I[1, 1]) * d[2]]
    c = scene.c_friction if scene.has("friction") else 0.0
    cI = [c, c, c] if full else list(c * d)
    m = float(scene.mass)
    g = np.asarray(scene.g, dtype=float)
    n = float(scene.orbit_rate) if scene.has("orbit") else 0.0
    k = 3 * n * n
    if full:
        gg = [float(v) for v in (k * I).ravel()]
    else:
        gg = [float(k * (I[2, 2] - I[1, 1]) * d[0]), k * (I[0, 0] - I[2, 2]) * d[1], k * (I[1, 1] - I[0, 0]) * d[2]]
        gg += [0.0] * 6
    params = [*I.ravel(), *Minv.ravel(), *eul, *cI, *(m * g), m, *scene.r_cm, *g, 1.0 / m, *gg, n]
    for fp in scene.force_points.values():
        params += list(fp.point)
    torque, speed = _torque_and_speed_rotors(scene)
    params += [scene.rotors[r].J for r in torque + speed] + [1.0 / scene.rotors[r].J for r in torque]
    for r in speed:
        rot = scene.rotors[r]
        params += [rot.k_f, rot.k_m, *(rot.position if rot.position is not None else (0.0, 0.0, 0.0))]
    return [float(v) for v in params]


def reference_inputs(scene: Scene, values: dict[str, float]) -> list[float]:
    """The reference kernel's inputs at one node (Inputs, read_inputs) from FMU input
    variable name -> value (missing names: 0)."""

    def vec(name: str) -> list[float]:
        return [float(values.get(f"{name}[{i}]", 0.0)) for i in (1, 2, 3)]

    out = vec("tau_body") + vec("tau_world") + vec("f_body") + vec("f_world")
    for name in scene.force_points:
        out += vec(f"f_{name}")
    out += vec("a_pivot")
    torque, speed = _torque_and_speed_rotors(scene)
    out += [float(values.get(f"u_{r}", 0.0)) for r in torque]
    for r in speed:
        out += [float(values.get(f"Omega_{r}", 0.0)), float(values.get(f"Omega_dot_{r}", 0.0))]
    return out


def _start_inputs(scene: Scene) -> dict[str, float]:
    """The FMU's input start values by variable name (the scene's schedules at t = 0)."""
    out: dict[str, float] = {}
    features = {"tau_body": "torque_body", "tau_world": "torque_world", "f_body": "force_body",
                "f_world": "force_world", "a_pivot": "moving_pivot"}  # fmt: skip
    names = [name for name, feature in features.items() if scene.has(feature)]
    for name in names + [f"f_{p}" for p in scene.force_points]:
        out.update({f"{name}[{i + 1}]": float(v) for i, v in enumerate(scene.input_start(name))})
    for r, rot in scene.rotors.items():
        for name in (f"Omega_{r}", f"Omega_dot_{r}") if rot.speed else (f"u_{r}",):
            out[name] = float(scene.input_start(name)[0])
    return out


def _start_state(scene: Scene) -> list[float]:
    """The FMU's start state: q, ω, (position, velocity), torque-mode rotor rates, orbit angle."""
    torque, _ = _torque_and_speed_rotors(scene)
    state = [*scene.q0, *scene.w0] + ([*scene.x0, *scene.v0] if scene.moves else [])
    state += [scene.rotors[r].Omega0 for r in torque]
    return state + ([0.0] if scene.has("orbit") else [])


def _compile_reference(scene: Scene, tmp: Path) -> list[str]:
    """Compile fmu/c/bench_reference.c for the scene's equations into `tmp`; returns its
    command line without the step count and the method: [exe, h, start state, parameters,
    inputs] at the scene's fixed step, start state and input start values."""
    exe = tmp / "reference"
    cmd = ["gcc", *[f for f in CFLAGS if f != "-fPIC"], "-Werror", *(f"-D{f}" for f in reference_features(scene)),
           str(REFERENCE), "-o", str(exe), "-lm"]  # fmt: skip
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"the C reference failed to compile for {scene.name}:\n{proc.stderr}")
    args = [*_start_state(scene), *reference_parameters(scene), *reference_inputs(scene, _start_inputs(scene))]
    return [str(exe), repr(float(scene.fixed_step)), *(repr(float(v)) for v in args)]


def _run_reference(cmd: list[str], n: int, method: str = "rk4") -> tuple[float, np.ndarray]:
    """(ns per step, best of 5 inside the process; the final state) of n reference steps
    of `method` ("rk4" or "rk8")."""
    order = {"rk4": "4", "rk8": "8"}[method]
    out = subprocess.run([cmd[0], str(n), order, *cmd[1:]], check=True, capture_output=True, text=True).stdout
    values = out.split()
    return float(values[0]), np.array([float(v) for v in values[1:]])


def reference_step_ns(scene: Scene, n: int = 4_000_000, method: str = "rk4") -> float:
    """ns per step of the minimal hand-written C kernel of the scene's equations
    (fmu/c/bench_reference.c, never part of an FMU), best of 5."""
    with tempfile.TemporaryDirectory() as tmp:
        return _run_reference(_compile_reference(scene, Path(tmp)), n, method)[0]


def reference_state(scene: Scene, n: int, method: str, x0: Sequence[float], inputs: dict[str, float]) -> np.ndarray:
    """The state after n reference steps of `method` from x0 (the FMU's state order) with
    the inputs (FMU variable name -> value) held (see generated_state)."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = _compile_reference(scene, Path(tmp))
        nx = len(_start_state(scene))
        args = [*x0, *reference_parameters(scene), *reference_inputs(scene, inputs)]
        cmd = cmd[:2] + [repr(float(v)) for v in args]
        assert len(cmd) == 2 + nx + len(reference_parameters(scene)) + len(reference_inputs(scene, inputs))
        return _run_reference(cmd, n + n % 2, method)[1]


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


def interleaved_step_ns(
    fmu: Path, scene: Scene, method: str = "rk4", pairs: int = BENCH_PAIRS, n: int = BENCH_STEPS
) -> Interleaved:
    """The FMU's fixed `method` step ("rk4" or "rk8") at `default_step` and the C reference
    of the scene's equations with the same method, each timed in `pairs` processes of n
    steps, run alternately (harness, reference, harness, ...): a slow spell of the machine
    then lands on both sides of a few pairs instead of deciding the ratio."""
    raw, fmi, ref = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        exe = _compile_harness(fmu, Path(tmp))
        ref_cmd = _compile_reference(scene, Path(tmp))
        h = default_step(fmu)
        for _ in range(pairs):
            r, f = _run_harness(exe, n, METHODS[method].value, h)
            raw.append(r)
            fmi.append(f)
            ref.append(_run_reference(ref_cmd, n, method)[0])
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
        if load_scene(name).has("central_gravity"):  # no reference kernel for it (reference_features)
            print(f"{name}: left out: the C reference has no central field")
            continue
        # inputs at zero: a step costs the same for any input value, and a thrust or torque
        # held over the 4e6 benchmark steps would spin the body up until the sub-step
        # limits refuse the step
        sc = dataclasses.replace(load_scene(name), inputs={})
        fmu = build_fmu(sc, out)
        sub = max(1, int(np.ceil(sc.step / sc.fixed_step - 1e-9)))
        us = fmpy_step_us(fmu, sc.step, sc.fixed_step)
        for method in REFERENCE_METHODS:
            # DOP853's step is ~3 times RK4's: fewer steps keep the process times alike
            iv = interleaved_step_ns(fmu, sc, method, n=BENCH_STEPS if method == "rk4" else BENCH_STEPS // 3)
            raw, fmi, ref = iv.median("raw"), iv.median("fmi"), iv.median("ref")
            lo, mid, hi = iv.ratio_spread()
            fm = us if method == "rk4" else float("nan")
            rows.append((name, method, raw, fmi, fmi / raw, sub, fm, fm * 1e3 / sub, ref, mid, lo, hi))
            nxs.append(len(_start_state(sc)))
            print(f"{name} {method}: raw {raw:.1f} ns, reference {ref:.1f} ns, {mid:.2f} ({lo:.2f}..{hi:.2f})",
                  flush=True)  # fmt: skip
    print(
        f"\n{'scene':<22}{'method':<7}{'raw C ns/step':>14}{'C ref ns':>9}{'raw/ref':>8}{'min..max':>12}"
        f"{'FMI ns/step':>12}{'FMI/raw':>9}{'substeps':>9}{'fmpy us/doStep':>15}{'fmpy ns/substep':>16}"
    )
    for r in rows:
        spread = f"{r[10]:.2f}..{r[11]:.2f}"
        fmpy = f"{r[6]:15.2f}{r[7]:16.1f}" if r[1] == "rk4" else f"{'':15}{'':16}"  # fmpy times rk4 only
        print(
            f"{r[0]:<22}{r[1]:<7}{r[2]:14.1f}{r[8]:9.1f}{r[9]:8.2f}{spread:>12}{r[3]:12.1f}{r[4]:9.3f}{r[5]:9d}{fmpy}"
        )
    print(
        "raw: the generated fixed step (no error estimate) in a C loop; C ref: a minimal hand-written C kernel of the "
        "same equations and method (fmu/c/bench_reference.c, benchmark only); fmpy: fixed RK4 steps. "
        "reaction_wheel_slew is the three-wheel gyrostat (issue 28)"
    )
    print(
        f"ns/step: medians over {BENCH_PAIRS} processes each of the harness and the reference, run alternately "
        f"(best of 5 repeats of {BENCH_STEPS:,} RK4 or {BENCH_STEPS // 3:,} RK8 steps inside each); raw/ref: median, "
        "min..max over the pairs"
    )
    # the target is for the 7-state body; a free body or a moving pivot has 13 states
    seven = [r[3] for r, nx in zip(rows, nxs) if nx == 7 and r[1] == "rk4"]
    if seven:
        worst = max(seven)
        print(
            f"\ntarget <= {TARGET_NS:.0f} ns per RK4 internal step of the 7-state body: worst scene {worst:.1f} ns "
            f"({'met' if worst <= TARGET_NS else 'NOT met'})"
        )
    worst_row = max(rows, key=lambda r: r[9])
    name, method, ratio = worst_row[0], worst_row[1], worst_row[9]
    print(
        f"target raw/ref <= {TARGET_REF_RATIO}: worst {name} {method} {ratio:.2f} (median; pairs "
        f"{worst_row[10]:.2f}..{worst_row[11]:.2f}) ({'met' if ratio <= TARGET_REF_RATIO else 'NOT met'}; "
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
