"""The benchmark's yardstick fmu/c/bench_reference.c for one scene: its features, parameters, inputs and runs.

The reference is a hand-written C RK4 and RK8 of a scene's equations (never part of an
FMU). `reference_features` chooses its equations by C macros, `reference_parameters`
computes once what depends on the parameters only (what an expert hoists out of the
step), `reference_inputs` lays out one node's inputs; `reference_command` compiles it with
the FMU's flags and gives the command line that runs it at the scene's fixed step, start
state and input start values. `reference_state` is what tests/report/test_benchmark_reference.py
compares with the generated step's state.
"""

from __future__ import annotations

import subprocess
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from modelsrc.scene import Scene

from ..build.compile import CFLAGS, gcc_version
from ..build.object_cache import cached_object, content_key

REFERENCE = Path(__file__).resolve().parent.parent / "c" / "bench_reference.c"


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


def torque_and_speed_rotors(scene: Scene) -> tuple[list[str], list[str]]:
    """(torque-mode, speed-mode) rotor names; ValueError for another mode (the C reference has none)."""
    names = list(scene.rotors)
    other = [n for n in names if scene.rotors[n].mode not in ("torque", "speed")]
    if other:
        raise ValueError(
            f"scene {scene.name}: rotor {other[0]} is in mode {scene.rotors[other[0]].mode!r}; the C reference "
            "(fmu/c/bench_reference.c) takes torque- and speed-mode rotors only"
        )
    return [n for n in names if not scene.rotors[n].speed], [n for n in names if scene.rotors[n].speed]


def _mass_matrix(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """(I about the rotation point, M = I − Σ_torque-mode J g gᵀ) (docs/theory.md §8.1, §8.5)."""
    I = _rotation_inertia(scene)
    M = I.copy()
    for name in torque_and_speed_rotors(scene)[0]:
        g = np.asarray(scene.rotors[name].axis, dtype=float)
        M = M - scene.rotors[name].J * np.outer(g, g)
    return I, M


def reference_features(scene: Scene) -> list[str]:
    """The C macros that select the scene's equations in fmu/c/bench_reference.c."""
    I, M = _mass_matrix(scene)
    flags = []
    off = ~np.eye(3, dtype=bool)
    full = bool(np.any(I[off] != 0.0) or np.any(M[off] != 0.0))
    if full:
        flags.append("REF_FULL_INERTIA")
    if scene.has("gravity") and not scene.has("translation"):
        flags.append("REF_GRAVITY")
    names = {"friction": "REF_FRICTION", "torque_body": "REF_TAU_BODY", "torque_world": "REF_TAU_WORLD",
             "prescribed_rate": "REF_PRESCRIBED", "translation": "REF_TRANSLATION", "moving_pivot": "REF_MOVING_PIVOT",
             "force_body": "REF_FORCE_BODY", "force_world": "REF_FORCE_WORLD", "orbit": "REF_ORBIT",
             "gravity_gradient": "REF_GRAVITY_GRADIENT", "central_gravity": "REF_CENTRAL"}  # fmt: skip
    flags += [macro for feature, macro in names.items() if scene.has(feature)]
    if scene.has("translation") and scene.has("gravity"):
        flags.append("REF_FREE_GRAVITY")
    points = list(scene.force_points.values())
    if points:
        world = sum(1 << k for k, fp in enumerate(points) if fp.frame == "world")
        flags += [f"REF_NPOINTS={len(points)}", f"REF_POINT_WORLD={world}"]
    torque, speed = torque_and_speed_rotors(scene)
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
    if not full and len({_rotor_axis(scene, n) for n in torque + speed}) == 3:
        flags.append("REF_HFORM")  # rotor momenta on every axis: w x (I w + h) is cheaper than Euler's form
    return flags


def reference_parameters(scene: Scene) -> list[float]:
    """What the reference kernel reads as parameters, computed once from the scene's
    (fmu/c/bench_reference.h, Params, read_params): I about the rotation point, M⁻¹ (the
    inverse of I − Σ J g gᵀ, I⁻¹ without rotors), Euler's coefficients (I_2 − I_3) M⁻¹_1
    (cyclic), the friction c M⁻¹_i (diagonal; c for a full tensor), the lever arm M⁻¹_i r_j
    (diagonal; r for a full tensor), the weight m g, m, g, 1/m, the gravity gradient's
    3 n² (I_3 − I_2) M⁻¹_1 (cyclic; 3 n² I for a full tensor), n, the central field's μ, tr I,
    1.5/m and 3 (I_3 − I_2) M⁻¹_1 (cyclic), the force points, the rotors' J, 1/J and M⁻¹_i J_k,
    the propellers' k_f, k_m and positions."""
    I, M = _mass_matrix(scene)
    Minv = np.linalg.inv(M)
    full = "REF_FULL_INERTIA" in reference_features(scene)
    d = np.diag(Minv)
    Id = np.diag(I)
    cyc = [(1, 2), (2, 0), (0, 1)]
    eul = [(Id[j] - Id[k]) * d[i] for i, (j, k) in enumerate(cyc)]
    c = scene.c_friction if scene.has("friction") else 0.0
    cI = [c, c, c] if full else list(c * d)
    r_cm = np.asarray(scene.r_cm, dtype=float)
    mr = [*r_cm, *[0.0] * 6] if full else [float(d[i] * r_cm[j]) for i in range(3) for j in range(3)]
    m = float(scene.mass)
    g = np.asarray(scene.g, dtype=float)
    n = float(scene.orbit_rate) if scene.has("orbit") else 0.0
    n3 = 3 * n * n
    gg = [float(v) for v in (n3 * I).ravel()] if full else [n3 * (Id[k] - Id[j]) * d[i] for i, (j, k) in enumerate(cyc)]
    gg += [0.0] * (9 - len(gg))
    mu = float(scene.mu) if scene.has("central_gravity") else 0.0
    gc = [0.0] * 3 if full else [3 * (Id[k] - Id[j]) * d[i] for i, (j, k) in enumerate(cyc)]
    params = [*I.ravel(), *Minv.ravel(), *eul, *cI, *mr, *(m * g), m, *g, 1.0 / m, *gg, n]
    params += [mu, float(np.trace(I)), 1.5 / m, *gc]
    for fp in scene.force_points.values():
        params += list(fp.point)
    torque, speed = torque_and_speed_rotors(scene)
    params += [scene.rotors[r].J for r in torque + speed] + [1.0 / scene.rotors[r].J for r in torque]
    params += [float(d[i] * scene.rotors[r].J) for i in range(3) for r in torque]
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
    torque, speed = torque_and_speed_rotors(scene)
    out += [float(values.get(f"u_{r}", 0.0)) for r in torque]
    for r in speed:
        out += [float(values.get(f"Omega_{r}", 0.0)), float(values.get(f"Omega_dot_{r}", 0.0))]
    return out


def start_inputs(scene: Scene) -> dict[str, float]:
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


def start_state(scene: Scene) -> list[float]:
    """The FMU's start state: q, ω, (position, velocity), torque-mode rotor rates, orbit angle."""
    torque, _ = torque_and_speed_rotors(scene)
    state = [*scene.q0, *scene.w0] + ([*scene.x0, *scene.v0] if scene.moves else [])
    state += [scene.rotors[r].Omega0 for r in torque]
    return state + ([0.0] if scene.has("orbit") else [])


def reference_command(scene: Scene, tmp: Path, features: Sequence[str] | None = None) -> list[str]:
    """Compile fmu/c/bench_reference.c for the scene's equations (`features`: other macros,
    for a test's mutants) into `tmp`; returns its command line without the method and the
    step counts (`reference_args`): [exe, h, start state, parameters, inputs] at the scene's
    fixed step, start state and input start values."""
    exe = tmp / "reference"
    macros = reference_features(scene) if features is None else features
    flags = [*(f for f in CFLAGS if f != "-fPIC"), "-Werror", *(f"-D{f}" for f in macros)]

    def compile_to(obj: Path) -> str:
        proc = subprocess.run(["gcc", *flags, "-c", str(REFERENCE), "-o", str(obj)], capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"the C reference failed to compile for {scene.name}:\n{proc.stderr}")
        return proc.stderr

    # the same macros compile to the same object: from the object cache (fmu/build/object_cache.py)
    obj, _, _ = cached_object(content_key(REFERENCE.parent, REFERENCE.name, f"gcc {gcc_version()}", flags), compile_to)
    proc = subprocess.run(["gcc", "-o", str(exe), str(obj), "-lm"], capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"the C reference failed to link for {scene.name}:\n{proc.stderr}")
    args = [*start_state(scene), *reference_parameters(scene), *reference_inputs(scene, start_inputs(scene))]
    return [str(exe), repr(float(scene.fixed_step)), *(repr(float(v)) for v in args)]


def reference_args(cmd: list[str], n: int, method: str = "rk4", repeats: int = 5) -> list[str]:
    """The command line of `repeats` runs of n reference steps of `method` ("rk4" or "rk8"),
    from `reference_command`'s."""
    order = {"rk4": "4", "rk8": "8"}[method]
    return [cmd[0], order, str(n), str(repeats), *cmd[1:]]


def run_reference(cmd: list[str], n: int, method: str = "rk4", repeats: int = 5) -> tuple[float, np.ndarray]:
    """(ns of CPU time per step, best of `repeats` runs inside the process; the final state)
    of n reference steps of `method` ("rk4" or "rk8")."""
    out = subprocess.run(reference_args(cmd, n, method, repeats), check=True, capture_output=True, text=True).stdout
    values = out.split()
    return float(values[0]), np.array([float(v) for v in values[1:]])


def reference_step_ns(scene: Scene, n: int = 4_000_000, method: str = "rk4") -> float:
    """ns of CPU time per step of the hand-written C kernel of the scene's equations
    (fmu/c/bench_reference.c, never part of an FMU), best of 5."""
    with tempfile.TemporaryDirectory() as tmp:
        return run_reference(reference_command(scene, Path(tmp)), n, method)[0]


def reference_state(
    scene: Scene,
    n: int,
    method: str,
    x0: Sequence[float],
    inputs: dict[str, float],
    features: Sequence[str] | None = None,
    parameters: Sequence[float] | None = None,
) -> np.ndarray:
    """The state after n reference steps of `method` from x0 (the FMU's state order) with
    the inputs (FMU variable name -> value) held (see fmu.bench.benchmark.generated_state);
    `features` and `parameters` replace the scene's (a test's mutants)."""
    params = reference_parameters(scene) if parameters is None else list(parameters)
    with tempfile.TemporaryDirectory() as tmp:
        cmd = reference_command(scene, Path(tmp), features)
        args = [*x0, *params, *reference_inputs(scene, inputs)]
        if len(x0) != len(start_state(scene)) or len(params) != len(reference_parameters(scene)):
            raise ValueError(f"{scene.name}: {len(x0)} states and {len(params)} parameters do not fit the reference")
        return run_reference(cmd[:2] + [repr(float(v)) for v in args], n + n % 2, method)[1]
