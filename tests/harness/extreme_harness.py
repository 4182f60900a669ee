"""Harness of the extreme-case tests: the FMU through ctypes, runs with sub-step counts, error formulas.

Stiff and extreme cases (tests/robustness/test_extreme_spin.py, tests/robustness/test_extreme_bodies.py): every
method stays stable, sub-steps or refuses clearly, and where an exact solution exists its
error is what the method's order predicts.

All runs go through the FMU's own binary via ctypes (tests/harness/fmi3_ctypes.py); the number
of internal steps of each doStep is read with a small accessor library compiled
against the FMU's headers (tests/c/introspect.c). One FMU (extreme_free: free principal
body, torque inputs, friction) is re-parametrised through start values for most cases;
the shipped sleeping_top covers gravity. Every test prints its measurements (pytest -s);
docs/robustness.md collects them.

Tolerances: the phase error of a method on a pure rotation is known in closed form from
its stability function R(z) (Hairer, Nørsett & Wanner I §IV.3, Hairer & Wanner II §IV.3):
e^{ix} - R(ix) = C_p (ix)^{p+1} + ..., with C = 1/120 (RK4), 1/12 (implicit midpoint),
1/720 and 1/100800 (Gauss 4, 6: (s!)^2/((2s)!(2s+1)!)). The unit quaternion of a spin W
turns at W/2, so after N = T/h steps the rotation-angle error is
    e_att = W T C (h W / 2)^p                                        (*)
Round-off floors: one rounding (eps) per internal step and state component, accumulated
at worst linearly (N eps), multiplied by the size of the quantity.
"""

from __future__ import annotations

import ctypes as C
import math
import os
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from modelsrc.methods import METHODS as METHOD_TABLE
from rbcheck.numerics.rotation_np import quat_to_matrix, rotation_angle_between

from .fmi3_ctypes import OK, Fmi3Library, extract_fmu, shared_fmu

EPS = np.finfo(float).eps
METHODS = tuple(METHOD_TABLE)
EXPLICIT = ("rk4", "rk8", "splitting", "exact_free")
# leading phase-error constant and order of (*) for the methods where it is known exactly
PHASE = {"rk4": (4, 1 / 120), "implicit_midpoint": (2, 1 / 12), "gauss4": (4, 1 / 720), "gauss6": (6, 1 / 100800)}
STATE_NAMES = ("q[1]", "q[2]", "q[3]", "q[4]", "w_body[1]", "w_body[2]", "w_body[3]")
OUT_NAMES = STATE_NAMES + (
    "E_kin",
    "E_total",
    "L_world[1]",
    "L_world[2]",
    "L_world[3]",
    "euler_zxz[1]",
    "euler_zxz[2]",
    "euler_zxz[3]",
)
# RBFMU_LONG_HORIZON=1: 1e7 internal steps for every method (about 3 min; the numbers of
# docs/robustness.md); by default the Gauss methods take fewer (their step costs 20-200x RK4's)
LONG = os.environ.get("RBFMU_LONG_HORIZON") == "1"


class Lib:
    """An FMU's loaded binary plus the accessors (substeps, work of the last doStep) built against its headers."""

    def __init__(self, kind: str, workdir: Path):
        fmu = shared_fmu(kind)
        self.fmi = Fmi3Library(extract_fmu(fmu, workdir / kind))
        src = self.fmi.unzipdir / "sources"
        acc = workdir / f"introspect_{kind}.so"
        proc = subprocess.run(
            [
                "gcc",
                "-O2",
                "-std=c99",
                "-fPIC",
                "-shared",
                "-Wall",
                "-Wextra",
                "-Werror",
                "-I",
                str(src),
                str(Path(__file__).resolve().parent.parent / "c" / "introspect.c"),
                "-o",
                str(acc),
            ],
            capture_output=True,
            text=True,
        )
        assert proc.returncode == 0, proc.stderr
        self.acc = C.CDLL(str(acc))
        self.acc.rbtest_last_substeps.restype = C.c_long
        self.acc.rbtest_last_substeps.argtypes = [C.c_void_p]
        self.acc.rbtest_last_work.restype = C.c_double
        self.acc.rbtest_last_work.argtypes = [C.c_void_p]
        self.method_value = {name: v for v, name in self.fmi.info.enum_items.items()}


@dataclass
class Run:
    """One co-simulation: outputs at the communication points, substeps per doStep, the
    status of the last doStep (OK when all succeeded), its log, wall time of the loop."""

    time: np.ndarray
    out: dict[str, np.ndarray]
    substeps: list[int]
    status: int
    log: list[str] = field(default_factory=list)
    wall: float = 0.0

    def vec(self, *names: str) -> np.ndarray:
        return np.column_stack([self.out[n] for n in names])

    @property
    def q(self) -> np.ndarray:
        return self.vec("q[1]", "q[2]", "q[3]", "q[4]")

    @property
    def w(self) -> np.ndarray:
        return self.vec("w_body[1]", "w_body[2]", "w_body[3]")


def simulate(
    lib: Lib, method: str, starts: dict[str, float], H: float, n: int, input_fn=None, names: tuple[str, ...] = OUT_NAMES
) -> Run:
    """n doSteps of H from t = 0 with start values `starts`; input_fn(t, outputs) -> inputs
    set before each step (closed loop). Stops at the first refused step."""
    info = lib.fmi.info
    names = tuple(n_ for n_ in names if n_ in info.vr)
    inst = lib.fmi.instantiate()
    try:
        keys = list(starts)
        assert inst.set_float64([info.vr[k] for k in keys], [float(starts[k]) for k in keys]) == OK, inst.log
        assert inst.set_int64([info.int64_vrs["method"]], [lib.method_value[method]]) == OK
        assert inst.enter_initialization_mode(0.0) == OK
        assert inst.exit_initialization_mode() == OK, inst.log
        vrs = [info.vr[k] for k in names]
        rows, subs, t, status = [inst.get_float64(vrs)[1]], [], 0.0, OK
        t0 = time.perf_counter()
        for _ in range(n):
            if input_fn is not None:
                u = input_fn(t, dict(zip(names, rows[-1])))
                assert inst.set_float64([info.vr[k] for k in u], list(u.values())) == OK
            status, _ = inst.do_step(t, H)
            if status != OK:
                break
            subs.append(lib.acc.rbtest_last_substeps(inst.handle))
            t += H
            rows.append(inst.get_float64(vrs)[1])
        wall = time.perf_counter() - t0
        arr = np.array(rows)
        return Run(
            H * np.arange(len(rows)),
            {k: arr[:, i] for i, k in enumerate(names)},
            subs,
            status,
            [m for _, _, m in inst.log],
            wall,
        )
    finally:
        inst.free()


def principal(I) -> dict[str, float]:
    return {f"I_principal[{k + 1}]": float(I[k]) for k in range(3)}


def omega0(w) -> dict[str, float]:
    return {f"w_body[{k + 1}]": float(w[k]) for k in range(3)}


def attitude_error(run: Run, q_ref: np.ndarray) -> np.ndarray:
    """Rotation angle (rad) between the FMU's and the reference attitude at each point."""
    return rotation_angle_between(quat_to_matrix(q_ref), quat_to_matrix(run.q))


def rel_drift(x: np.ndarray) -> float:
    return float(np.max(np.abs(x / x[0] - 1.0)))


def norm_L(run: Run) -> np.ndarray:
    return np.linalg.norm(run.vec("L_world[1]", "L_world[2]", "L_world[3]"), axis=1)


def min_substeps(method: str, H: float, rate: float, h_max: float, spin: float | None = None) -> int:
    """Substeps the layer must take at least: h <= h_max, h * |w| <= the method's rotation
    limit and, for methods with a stability limit, h * ||df/dx|| <= that limit
    (docs/theory.md §5.4). rate: a lower bound of ||df/dx||; spin: |w| (default: rate,
    right for the fast-spin cases where the spin dominates)."""
    spin = rate if spin is None else spin
    n = max(math.ceil(H / h_max * (1 - 1e-12)), math.ceil(H * spin / METHOD_TABLE[method].rotation_limit * (1 - 1e-12)))
    limit = METHOD_TABLE[method].rate_limit
    return max(n, math.ceil(H * rate / limit)) if math.isfinite(limit) else n


def report(case: str, method: str, **numbers) -> None:
    """One line of measurements (pytest -s shows them; docs/robustness.md quotes them)."""
    text = " ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in numbers.items())
    print(f"\n[{case}] {method:17s} {text}", end="")
