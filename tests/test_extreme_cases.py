"""Stiff and extreme cases: every method stays stable, sub-steps or refuses clearly,
and where an exact solution exists its error is what the method's order predicts.

All runs go through the FMU's own binary via ctypes (tests/fmi3_ctypes.py); the number
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
import pytest

from modelsrc.errors import ModelInputError
from modelsrc.methods import METHODS as METHOD_TABLE
from modelsrc.scene import load_scene
from rbcheck import free_asymmetric, free_symmetric
from rbcheck.heavy_top import HeavyTop, TopParams, init_from_state, sleeping_threshold
from rbcheck.rotation_np import quat_to_matrix, rotation_angle_between

from .conftest import write_scene
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
    """An FMU's loaded binary plus the substep accessor built against its headers."""

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
                str(Path(__file__).parent / "c" / "introspect.c"),
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


@pytest.fixture(scope="module")
def free(tmp_path_factory) -> Lib:
    return Lib("extreme_free", tmp_path_factory.mktemp("extreme"))


@pytest.fixture(scope="module")
def top(tmp_path_factory) -> Lib:
    return Lib("sleeping_top", tmp_path_factory.mktemp("top"))


def report(case: str, method: str, **numbers) -> None:
    """One line of measurements (pytest -s shows them; docs/robustness.md quotes them)."""
    text = " ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in numbers.items())
    print(f"\n[{case}] {method:17s} {text}", end="")


# ---------------------------------------------------------------------------------------
# Fast spin about a principal axis: exact solution w = const, q turning uniformly
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("W", [1e4, 1e5])
@pytest.mark.parametrize("method", METHODS)
def test_fast_spin_default_h_max(free, method, W):
    """|w| = W about axis 3, communication step 1e-2 s, h_max 1e-3 s (h_max W = 10 and
    100 rad): explicit methods must sub-step to their stability limit on their own, all
    methods keep w exact (it is an equilibrium of Euler's equations), |q| = 1 and E, |L|
    constant; the attitude error is measured (it is O(1) rad for every method but the
    splitting, whose free flow is exact here: h_max sets accuracy, the guard only stability)."""
    H, n, h_max = 1e-2, 10, 1e-3
    run = simulate(free, method, {"h_max": h_max, **omega0((0, 0, W))}, H, n)
    assert run.status == OK, run.log
    need = min_substeps(method, H, W, h_max)
    assert min(run.substeps) >= need, (run.substeps, need)
    # w stays (0, 0, W): the Euler right-hand side is exactly zero there; Newton's dense
    # solve may leave round-off (measured <= 1e-18 W), bound 1e-13 W
    assert np.max(np.abs(run.w - [0, 0, W])) <= 1e-13 * W
    assert np.max(np.abs(np.linalg.norm(run.q, axis=1) - 1)) <= 4 * EPS  # projected every step
    t = run.time
    q_exact = np.column_stack([np.cos(W * t / 2), 0 * t, 0 * t, np.sin(W * t / 2)])
    err = attitude_error(run, q_exact)
    if method == "splitting":  # exact flow: round-off of the rotation angle W t, N eps W T
        assert err[-1] <= 10 * EPS * W * t[-1]
    report(
        f"fast spin W={W:g}",
        method,
        substeps=run.substeps[0],
        h_W=H / run.substeps[0] * W,
        att_err=float(err[-1]),
        wall_ms=run.wall * 1e3,
    )


@pytest.mark.parametrize("method", METHODS)
def test_fast_spin_phase_error_matches_theory(free, method):
    """W = 1e4 rad/s with h_max chosen for accuracy (h W / 2 = 0.05, or 0.02 where the
    method's rotation limit is smaller, so the FMU takes exactly that step): the attitude
    error after T = 0.1 s equals (*) within 5 % (the next term is O((hW/2)^2) <= 0.25 %
    relative); rk8 and the splittings are exact up to round-off here (rk8's error ~
    (0.05)^9 W T; a pure principal spin is an exact axis flow)."""
    W, T = 1e4, 0.1
    x = 0.05 if METHOD_TABLE[method].rotation_limit >= 0.1 else 0.02
    h = 2 * x / W
    run = simulate(free, method, {"h_max": h, **omega0((0, 0, W))}, 1e-2, int(round(T / 1e-2)))
    t = run.time
    err = attitude_error(run, np.column_stack([np.cos(W * t / 2), 0 * t, 0 * t, np.sin(W * t / 2)]))[-1]
    if method in PHASE:
        p, c = PHASE[method]
        predicted = W * T * c * x**p
        assert abs(err / predicted - 1) < 0.05, (err, predicted)
    else:
        predicted = 0.0
        assert err <= 10 * EPS * W * T  # round-off of the angle W T over N steps
    report(f"phase error W=1e4, hW/2={x}", method, att_err=float(err), predicted=predicted)


# ---------------------------------------------------------------------------------------
# Fast spin with a small off-axis component: closed forms rbcheck.free_symmetric/_asymmetric
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("I", [(1.0, 2.0, 3.0), (2.0, 2.0, 3.0)], ids=["asymmetric", "symmetric"])
@pytest.mark.parametrize("method", METHODS)
def test_fast_off_axis_spin_accurate_step(free, method, I):
    """w0 = (1e-3 W, 0, W), W = 1e4, h W/2 = 0.05: errors against the closed forms. The
    attitude error is the principal-axis phase error (*) up to the small transverse
    motion (bound: 2x (*)). The transverse w (amplitude A = 1e-3 W) turns at
    nu = W sqrt((I3-I1)(I3-I2)/(I1 I2)) (W for diag(1,2,3), W/2 for diag(2,2,3)); its phase
    error after T is nu T C (h nu)^p, so |dw| <= 2 A nu T C (h nu)^p (factor 2: measured
    0.9 and 0.45 of the estimate). rk8 is at round-off; the splitting (order 2, constant
    unknown) is only reported."""
    W, T, x = 1e4, 0.1, 0.05
    h = 2 * x / W
    w0 = np.array([1e-3 * W, 0.0, W])
    run = simulate(free, method, {"h_max": h, **principal(I), **omega0(w0)}, 1e-2, int(round(T / 1e-2)))
    assert run.status == OK
    t = run.time
    if I[0] == I[1]:
        w_ref, q_ref = free_symmetric.solve(I[0], I[2], w0, [1, 0, 0, 0], t)
    else:
        w_ref, q_ref = free_asymmetric.solve(np.array(I), w0, np.array([1.0, 0, 0, 0]), t)
    att = float(np.max(attitude_error(run, q_ref)))
    werr = float(np.max(np.abs(run.w - w_ref)))
    N = sum(run.substeps)
    floor_w, floor_att = N * EPS * W, N * EPS * W * T  # round-off of w and of the angle W T
    if method in PHASE:
        p, c = PHASE[method]
        nu = W * math.sqrt((I[2] - I[0]) * (I[2] - I[1]) / (I[0] * I[1]))
        assert att <= 2 * W * T * c * x**p + floor_att, att
        assert werr <= 2 * 1e-3 * W * nu * T * c * (h * nu) ** p + floor_w, werr
    elif method == "rk8":  # order 8: (0.1)^8 W T ~ 1e-5 times its small constant; measured 7e-12
        assert att <= 1e-9 and werr <= 1e-9 * W
    report(f"off-axis W=1e4 I={I}", method, att_err=att, w_err_rel=werr / W)


@pytest.mark.parametrize("W", [1e4, 1e5])
@pytest.mark.parametrize("method", METHODS)
def test_fast_off_axis_spin_default_h_max_stays_bounded(free, method, W):
    """Default h_max = 1e-3 s: bounded, finite, |q| = 1, |L| and E to the method's level
    (Gauss: exact quadratic invariants; splitting: exact |L|); errors vs the closed form
    recorded. Explicit methods at their stability limit."""
    I = (1.0, 2.0, 3.0)
    w0 = np.array([1e-3 * W, 0.0, W])
    run = simulate(free, method, {**principal(I), **omega0(w0)}, 1e-2, 10)
    assert run.status == OK and np.all(np.isfinite(run.vec(*STATE_NAMES)))
    assert min(run.substeps) >= min_substeps(method, 1e-2, W, 1e-3)
    assert np.max(np.abs(np.linalg.norm(run.q, axis=1) - 1)) <= 4 * EPS
    dE, dL = rel_drift(run.out["E_kin"]), rel_drift(norm_L(run))
    if method in ("implicit_midpoint", "gauss4", "gauss6"):
        assert dE <= 1e-13 and dL <= 1e-13  # quadratic invariants, Newton tolerance 1e-14
    elif method == "splitting":  # exact rotations: |L| to round-off, at worst N eps over N substeps
        assert dL <= max(1e-13, sum(run.substeps) * EPS)
    else:  # rk4/rk8: the transverse motion holds ~(1e-3)^2 of E and L: even losing it all
        assert dE <= 1e-5 and dL <= 1e-5  # (numerical damping at h*rate ~ 1) stays below 1e-5
    w_ref, q_ref = free_asymmetric.solve(np.array(I), w0, np.array([1.0, 0, 0, 0]), run.time)
    report(
        f"off-axis W={W:g} default h_max",
        method,
        substeps=run.substeps[0],
        dE=dE,
        dL=dL,
        att_err=float(np.max(attitude_error(run, q_ref))),
        w_err_rel=float(np.max(np.abs(run.w - w_ref))) / W,
    )


@pytest.mark.parametrize("method", METHODS)
def test_fast_symmetric_top_default_h_max_keeps_its_invariants(free, method):
    """A free symmetric top (2, 2, 3) spun at W = 1e4 with w_perp = 1e-3 W, default
    h_max: |w_perp| is exactly constant (docs/theory.md §2.3; rbcheck.free_symmetric),
    and so is E. 'Never garbage': |w_perp| within 10 % and E within 1e-3 over 1 s (1600
    revolutions) with whatever step the FMU chose."""
    W = 1e4
    run = simulate(free, method, {**principal((2.0, 2.0, 3.0)), **omega0((1e-3 * W, 0, W))}, 1e-2, 100)
    assert run.status == OK
    w_perp = np.hypot(run.out["w_body[1]"], run.out["w_body[2]"])
    dev, dE = float(np.max(np.abs(w_perp / (1e-3 * W) - 1))), rel_drift(run.out["E_kin"])
    report("symmetric top W=1e4 default h_max, 1 s", method, substeps=run.substeps[0], w_perp_dev=dev, dE=dE)
    assert dev <= 0.1 and dE <= 1e-3


# ---------------------------------------------------------------------------------------
# Thin rod, stiff inertia ratios; near-sphere; flat plate
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "I",
    [(1e-6, 1.0, 1.0 + 1e-6), (1e-9, 1.0, 1.0 + 1e-9), (1e-3, 1.0, 1.0 + 1e-3)],
    ids=["rod1e-6", "rod1e-9", "rod1e-3"],
)
@pytest.mark.parametrize("method", METHODS)
def test_thin_rod(free, method, I):
    """Nearly a rod (I1 << I2 ~ I3, the triangle inequality nearly tight) tumbling with w0 =
    (1, 0.5, 1) for 1 s, default steps: vs rbcheck.free_asymmetric (which agrees with a
    DOP853 solution at rtol 1e-13 to 1e-13 here). Every method is stable and keeps E and
    |L|; all but the splitting are accurate. The splitting's w error grows like h^2/I1
    (its axis flows exchange L1 with the others; divided by I1 it becomes w1): reported."""
    w0 = np.array([1.0, 0.5, 1.0])
    run = simulate(free, method, {**principal(I), **omega0(w0)}, 1e-2, 100)
    assert run.status == OK and np.all(np.isfinite(run.vec(*STATE_NAMES)))
    w_ref, q_ref = free_asymmetric.solve(np.array(I), w0, np.array([1.0, 0, 0, 0]), run.time)
    werr, att = float(np.max(np.abs(run.w - w_ref))), float(np.max(attitude_error(run, q_ref)))
    dE, dL = rel_drift(run.out["E_kin"]), rel_drift(norm_L(run))
    # |L| and E: 1000 internal steps, round-off N eps ~ 2e-13 (splitting's E: O(h^2) ~ 1e-8)
    assert dL <= 1e-12
    assert dE <= (1e-7 if method == "splitting" else 1e-12)
    if method != "splitting":
        # h w ~ 1.5e-3: order-2 midpoint ~ T w (h w)^2/12 ~ 3e-7; higher orders ~ round-off; the
        # reference and the conditioning of w1 = L1/I1 add ~1e-9 at I1 = 1e-9 (measured)
        assert werr <= 1e-6 and att <= 1e-6
    report(f"thin rod I1={I[0]:g}", method, w_err=werr, att_err=att, dE=dE, dL=dL)


@pytest.mark.parametrize("method", METHODS)
def test_near_sphere_keeps_E_and_L_to_round_off(free, method):
    """I = (1, 1+1e-12, 1+2e-12): w nearly constant; 1000 doSteps of 10 substeps (N = 1e4):
    |L| and E constant to round-off, bounded by N eps (one rounding per step, worst case
    linear accumulation); |q| = 1 to 4 eps. w drift is reported (physically < 1e-11)."""
    w0 = np.array([0.3, 1.0, -0.7])
    run = simulate(free, method, {**principal((1.0, 1.0 + 1e-12, 1.0 + 2e-12)), **omega0(w0)}, 1e-2, 1000)
    N = sum(run.substeps)
    dE, dL = rel_drift(run.out["E_kin"]), rel_drift(norm_L(run))
    assert dE <= N * EPS and dL <= N * EPS, (dE, dL, N * EPS)
    assert np.max(np.abs(np.linalg.norm(run.q, axis=1) - 1)) <= 4 * EPS
    report(
        "near sphere",
        method,
        N=N,
        dE_per_Neps=dE / (N * EPS),
        dL_per_Neps=dL / (N * EPS),
        w_drift=float(np.max(np.abs(run.w - w0))),
    )


@pytest.mark.parametrize("I", [(0.25, 0.75, 1.0), (1.0, 1.0, 2.0)], ids=["plate", "square_plate"])
@pytest.mark.parametrize("method", METHODS)
def test_flat_plate_at_triangle_equality_runs(free, method, I):
    """I3 = I1 + I2 exactly (a flat plate) is valid and runs: vs the closed forms, 10 s."""
    w0 = np.array([0.3, 1.0, -0.7])
    run = simulate(free, method, {**principal(I), **omega0(w0)}, 1e-2, 1000)
    assert run.status == OK
    if I[0] == I[1]:
        w_ref, q_ref = free_symmetric.solve(I[0], I[2], w0, [1, 0, 0, 0], run.time)
    else:
        w_ref, q_ref = free_asymmetric.solve(np.array(I), w0, np.array([1.0, 0, 0, 0]), run.time)
    werr, att = float(np.max(np.abs(run.w - w_ref))), float(np.max(attitude_error(run, q_ref)))
    # h w ~ 1.3e-3, T = 10 s: midpoint/splitting (order 2) ~ T w (h w)^2 ~ 2e-5; others ~ round-off
    assert werr <= (1e-4 if method in ("implicit_midpoint", "splitting") else 1e-10)
    report(f"flat plate I={I}", method, w_err=werr, att_err=att)


def test_just_past_the_triangle_equality_is_rejected(tmp_path, free):
    """I3 = I1 + I2 + 1e-10 violates the triangle inequality beyond its tolerance
    (1e-12 tr I, docs/theory.md §3.4): refused at scene load and at FMU initialisation;
    + 1e-13 is within the tolerance and accepted by both."""
    for delta, ok in ((1e-13, True), (1e-10, False), (3e-9, False)):
        text = f"[body]\nprincipal_moments = [1.0, 2.0, {3.0 + delta!r}]\n[initial]\nw_body = [1.0, 0.0, 0.0]\n"
        path = write_scene(tmp_path, text, f"plate_{'ok' if ok else 'bad'}_{int(-math.log10(delta))}")
        if ok:
            load_scene(path)
        else:
            with pytest.raises(ModelInputError, match=r"I_i \+ I_j >= I_k") as exc:
                load_scene(path)
            assert str(path) in str(exc.value) and "body.principal_moments" in str(exc.value)
        inst = free.fmi.instantiate()
        assert inst.set_float64([free.fmi.info.vr["I_principal[3]"]], [3.0 + delta]) == OK
        assert inst.enter_initialization_mode(0.0) == OK
        status = inst.exit_initialization_mode()
        errors = "\n".join(inst.errors_since(0))
        inst.free()
        assert (status == OK) == ok, errors
        if not ok:
            assert "I_i + I_j >= I_k" in errors and f"I_principal[3]={3.0 + delta:.17g}" in errors


# ---------------------------------------------------------------------------------------
# Sleeping top: exactly vertical, and at (1 +- 1e-3) x the threshold
# ---------------------------------------------------------------------------------------


def _top_params() -> tuple[TopParams, float]:
    sc = load_scene("sleeping_top")
    m, l = sc.mass, float(sc.r_cm[2])
    I1 = sc.inertia[0, 0] + m * l**2  # about the pivot (parallel axes, docs/theory.md §3.2)
    p = TopParams(I1, sc.inertia[2, 2], m, -float(sc.g[2]), l)
    return p, sleeping_threshold(p.I1, p.I3, p.M, p.g, p.l)


@pytest.mark.parametrize("factor", [1 - 1e-3, 1 + 1e-3])
@pytest.mark.parametrize("method", METHODS)
def test_sleeping_top_exactly_vertical(top, method, factor):
    """theta = 0 exactly (q = 1): gravity's torque is exactly zero, the quaternion state has
    no singularity there, so the top stays vertical (even below the threshold: an
    unstable equilibrium kept exactly) and the z-x-z outputs stay finite (the layer sets
    psi = 0 at the gimbal lock, docs/theory.md §1.3). 1 s, 1e4 internal steps."""
    _, wc = _top_params()
    run = simulate(
        top,
        method,
        {"c_friction": 0.0, "q[1]": 1.0, "q[2]": 0.0, "q[3]": 0.0, "q[4]": 0.0, **omega0((0, 0, factor * wc))},
        1e-2,
        100,
    )
    assert run.status == OK
    eul = run.vec("euler_zxz[1]", "euler_zxz[2]", "euler_zxz[3]")
    assert np.all(np.isfinite(eul))
    # theta stays 0 up to the Newton residual of the Gauss methods (relative 1e-14 of |Z|)
    assert np.max(run.out["euler_zxz[2]"]) <= 1e-12
    # the spin angle phi + psi advances as w3 t: the attitude is right, not just finite; error (*)
    # with h = 1e-4 (the scene's h_max), or round-off N eps w3 T for rk8/splitting (exact flow)
    angle = np.unwrap(eul[:, 0] + eul[:, 2])
    w3, T, N = factor * wc, run.time[-1], sum(run.substeps)
    p, c = PHASE.get(method, (8, 0.0))
    bound = w3 * T * c * (1e-4 * w3 / 2) ** p + 10 * N * EPS * w3 * T
    assert np.max(np.abs(angle - angle[0] - w3 * run.time)) <= bound
    report(f"sleeping top theta=0 w3={factor:g}x", method, theta_max=float(np.max(run.out["euler_zxz[2]"])))


@pytest.mark.parametrize("factor", [1 - 1e-3, 1 + 1e-3])
@pytest.mark.parametrize("method", METHODS)
def test_sleeping_top_near_threshold(top, method, factor):
    """Tilt 1 mrad, w3 = (1 -+ 1e-3) x threshold, no friction: the nutation amplitude of
    the closed form (rbcheck.heavy_top) is 92x (below) and 22x (above) the start tilt, and
    the FMU follows theta(t) over half a nutation period. Tolerance relative to the
    amplitude: near the threshold the amplitude amplifies the per-step error ~1/(2e-3);
    with h w3 = 1.2e-2: order 2 -> 500 (h w3)^2 = 7e-2, order >= 4 -> 1e-4 (>> 500 (h w3)^4)."""
    params, wc = _top_params()
    from modelsrc.quaternion import quat_from_euler_zxz

    q0 = quat_from_euler_zxz(0.0, 1e-3, 0.0)
    w0 = np.array([0.0, 0.0, factor * wc])
    ref = HeavyTop(params, init_from_state(q0, w0))
    T = 0.5 * ref.period + 0.05
    run = simulate(
        top, method, {"c_friction": 0.0, **{f"q[{k + 1}]": q0[k] for k in range(4)}, **omega0(w0)}, 1e-2, int(T / 1e-2)
    )
    assert run.status == OK
    theta_ref = ref.angles(run.time)[0]
    amp = float(np.arccos(ref.u1))
    err = float(np.max(np.abs(run.out["euler_zxz[2]"] - theta_ref))) / amp
    order2 = method in ("implicit_midpoint", "splitting")
    assert err <= (7e-2 if order2 else 1e-4), err
    dE = float(np.max(np.abs(run.out["E_total"] - run.out["E_total"][0])) / abs(run.out["E_kin"][0]))
    report(
        f"sleeping top tilt 1e-3 w3={factor:g}x",
        method,
        ref_amplitude=amp,
        fmu_amplitude=float(np.max(run.out["euler_zxz[2]"])),
        rel_err=err,
        dE_rel=dE,
    )


# ---------------------------------------------------------------------------------------
# Stiff friction
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", METHODS)
def test_stiff_friction(free, method):
    """c/I1 = 1e6 1/s (c = 1e6 N m s, I = (1, 2, 3)), communication step 1e-2: explicit
    methods sub-step to h c/I <= limit on their own, implicit ones are stable at h = 1e-3
    (h c/I = 1e3); the energy never increases from one communication point to the next
    (friction only removes energy). The exact E(1e-2) is ~E0 e^-6667 = 0: the Gauss
    methods are A- but not L-stable (|R(-1e3)| ~ 1), so they leave most of E: reported."""
    run = simulate(free, method, {"c_friction": 1e6, **omega0((1.0, 2.0, -3.0))}, 1e-2, 20)
    assert run.status == OK, run.log
    E = run.out["E_kin"]
    assert np.all(np.isfinite(E)) and np.all(np.diff(E) <= 0), E
    if method in EXPLICIT:  # rk4/rk8 sub-step to their stability limit; the splitting's friction flow is exact
        assert min(run.substeps) >= min_substeps(method, 1e-2, 1e6, 1e-3, spin=float(np.sqrt(14.0)))
        assert E[1] <= 1e-12 * E[0]  # resolved: gone after one communication step
    report(
        "stiff friction c/I=1e6",
        method,
        substeps=run.substeps[0],
        E1_over_E0=float(E[1] / E[0]),
        E20_over_E0=float(E[-1] / E[0]),
        wall_ms=run.wall * 1e3,
    )


@pytest.mark.parametrize("method", METHODS)
def test_stiffer_friction_explicit_refuse_implicit_run(free, method):
    """c/I1 = 1e11: RK4 and RK8 would need 1e9 > 1e8 substeps per 1e-2 s and must refuse
    with a message saying what to do; the implicit methods step (and E decreases), and so
    does the splitting, whose friction flow e^{-c h/I} is exact at any step."""
    run = simulate(free, method, {"c_friction": 1e11, **omega0((1.0, 2.0, -3.0))}, 1e-2, 3)
    if method in ("rk4", "rk8"):
        assert run.status != OK and len(run.substeps) == 0
        text = "\n".join(run.log)
        assert "more than the limit 100000000" in text and "choose an implicit method" in text, text
    else:
        assert run.status == OK and np.all(np.diff(run.out["E_kin"]) <= 0)
    report("stiff friction c/I=1e11", method, refused=run.status != OK)


# ---------------------------------------------------------------------------------------
# Long horizon: 1e7 internal steps
# ---------------------------------------------------------------------------------------

LONG_STEPS = {
    "rk4": 10_000,
    "rk8": 10_000,
    "splitting": 10_000,
    "exact_free": 1_000,
    "implicit_midpoint": 1_000,
    "gauss4": 300,
    "gauss6": 100,
}


@pytest.mark.parametrize("method", METHODS)
def test_long_horizon(free, method):
    """Tennis racket (I = (1, 2, 3), w0 = (0.01, 1, 0.01)), h_max 1e-5, doSteps of 1e-2
    (1000 substeps each): 1e4 doSteps = 1e7 internal steps for the explicit methods (and
    for all with RBFMU_LONG_HORIZON=1). Drift of |q| - 1, E and |L|: round-off only (the
    truncation error at h w = 1e-5 is < 1e-20 per step for order >= 2 ... except the
    splitting's bounded O(h^2) energy error, ~1e-10) -> bound N eps, the worst case."""
    n = 10_000 if LONG else LONG_STEPS[method]
    run = simulate(
        free,
        method,
        {"h_max": 1e-5, **omega0((0.01, 1.0, 0.01))},
        1e-2,
        n,
        names=STATE_NAMES + ("E_kin", "L_world[1]", "L_world[2]", "L_world[3]"),
    )
    assert run.status == OK and set(run.substeps) == {1000}
    N = sum(run.substeps)
    dq = float(np.max(np.abs(np.linalg.norm(run.q, axis=1) - 1)))
    dE, dL = rel_drift(run.out["E_kin"]), rel_drift(norm_L(run))
    assert dq <= 4 * EPS
    assert dL <= N * EPS
    assert dE <= (N * EPS + 1e-9 if method == "splitting" else N * EPS)
    report(
        "long horizon",
        method,
        internal_steps=N,
        dq=dq,
        dE=dE,
        dL=dL,
        dE_per_sqrtN_eps=dE / (math.sqrt(N) * EPS),
        wall_s=run.wall,
    )


# ---------------------------------------------------------------------------------------
# Torque steps of 1e6 N m, torques switching sign every step (closed loop)
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("h_max", [1e-3, 1e-6])
@pytest.mark.parametrize("method", METHODS)
def test_torque_step_1e6(free, method, h_max):
    """From rest, tau = 1e6 N m about principal axis 3 (I3 = 3): exactly w3 = tau t/I3,
    attitude angle tau t^2/(2 I3). w is linear in t, which every method integrates
    exactly: error = round-off, N eps w. The body spins up to 3.3e4 rad/s within 0.1 s:
    explicit methods re-step when the end-of-step rate exceeds their limit. Attitude
    error reported; with h_max 1e-6 (h w <= 0.033) it must be small: (*) with W = w_max."""
    tau, I3, H, n = 1e6, 3.0, 1e-2, 10
    run = simulate(free, method, {"h_max": h_max, **omega0((0, 0, 0)), "tau_body[3]": tau}, H, n)
    assert run.status == OK, run.log
    t = run.time
    N = sum(run.substeps)
    w_exact = tau * t / I3
    assert np.max(np.abs(run.out["w_body[3]"] - w_exact)) <= N * EPS * w_exact[-1] + 1e-12
    assert np.max(np.abs(run.w[:, :2])) <= 1e-12 * w_exact[-1]
    angle = tau * t**2 / (2 * I3)
    att = float(np.max(attitude_error(run, np.column_stack([np.cos(angle / 2), 0 * t, 0 * t, np.sin(angle / 2)]))))
    # re-stepped as the body spins up: the final steps within twice the rotation limit
    assert H / run.substeps[-1] * w_exact[-1] <= 2 * METHOD_TABLE[method].rotation_limit
    if h_max == 1e-6:
        W = w_exact[-1]
        p, c = PHASE.get(method, (8, 0.0))
        # (*) at the final (largest) rate, plus round-off of the angle: N eps angle
        bound = (W * t[-1] * c * (h_max * W / 2) ** p if c else 0.0) + N * EPS * angle[-1]
        assert att <= bound, (att, bound)
    report(
        f"torque step 1e6 h_max={h_max:g}",
        method,
        substeps_first_last=f"{run.substeps[0]}/{run.substeps[-1]}",
        w_err_rel=float(np.max(np.abs(run.out["w_body[3]"] - w_exact)) / w_exact[-1]),
        att_err=att,
        angle=float(angle[-1]),
    )


@pytest.mark.parametrize("method", METHODS)
def test_torque_switching_sign_every_step(free, method):
    """Closed loop: tau3 = +1e6 N m while w3 < tau H/(2 I3), else -1e6, so it flips every
    step; exact response at the communication points: w3 alternates 0, tau H/I3 (3333
    rad/s), and the attitude angle grows by tau H^2/(2 I3) per step. h_max 1e-5 (h w <=
    0.033)."""
    tau, I3, H, n = 1e6, 3.0, 1e-2, 20

    def bang_bang(t, out):
        return {"tau_body[3]": -tau if out["w_body[3]"] > tau * H / (2 * I3) else tau}

    run = simulate(free, method, {"h_max": 1e-5, **omega0((0, 0, 0))}, H, n, input_fn=bang_bang)
    assert run.status == OK
    k = np.arange(len(run.time))
    w_exact = np.where(k % 2 == 1, tau * H / I3, 0.0)
    N = sum(run.substeps)
    werr = float(np.max(np.abs(run.out["w_body[3]"] - w_exact)))
    assert werr <= N * EPS * tau * H / I3
    angle = k * tau * H**2 / (2 * I3)
    att = float(np.max(attitude_error(run, np.column_stack([np.cos(angle / 2), 0 * k, 0 * k, np.sin(angle / 2)]))))
    W = tau * H / I3
    p, c = PHASE.get(method, (8, 0.0))
    assert att <= (W * H * n * c * (1e-5 * W / 2) ** p if c else 0.0) + N * EPS * angle[-1]
    report("bang-bang 1e6 N m", method, w_err_rel=werr / W, att_err=att, angle=float(angle[-1]))
