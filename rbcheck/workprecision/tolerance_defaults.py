"""Default settings of the report's error-control part: a free body at 1e4 and 1e5 rad/s, and every scene as shipped.

Both run the FMU without choosing a step: the scene's default method, tolerance and
h_max (modelsrc.scene.default_method: exact_free for a torque-free body, else rk8 at
DEFAULT_TOLERANCE), and rk8 at DEFAULT_TOLERANCE beside them. The target (docs/user_guide.md,
defaults): relative state error e_ω/Ω and attitude error e_R (rad) below 1e-8 at the end,
relative |L| and E drifts below 1e-9.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from modelsrc.methods import DEFAULT_TOLERANCE, error_controlled
from modelsrc.scene import Scene, load_scene

from ..baselines.rigid_body import comm_grid
from ..closed_forms import free_asymmetric
from .config import Config
from .harness import advance, show
from .references import Reference, errors, make_reference
from .tolerance import EPS, ControlDriver, ControlPoint

if TYPE_CHECKING:
    from tqdm import tqdm

# The targets of the defaults: end-time error (relative state, attitude in rad) and drifts.
TARGET_ERROR = 1e-8
TARGET_DRIFT = 1e-9


@dataclass
class DefaultRun:
    """One run at default settings: what ran (`case`, `setting`), over T (s) with
    communication step `step` (s), the reference's name and its error estimate, and the
    measured point (errors, drifts, steps, wall time); omega_scale: the reference's
    largest |ω| component (rad/s), the scale of the relative state error e_ω/Ω; defaults:
    the FMU's shipped settings (else a setting the report chose)."""

    case: str
    setting: str
    T: float
    step: float
    source: str
    ref_floor: float
    omega_scale: float
    point: ControlPoint
    defaults: bool = False

    @property
    def met(self) -> bool:
        """Errors below TARGET_ERROR and every measured drift below TARGET_DRIFT (NaN: not
        a conserved quantity of the scene, not counted)."""
        p = self.point
        drift_ok = all(not (d > TARGET_DRIFT) for d in (p.drift_E, p.drift_L))
        return p.err <= TARGET_ERROR and drift_ok


def spin_reference(scene: Scene, w0: np.ndarray, grid: np.ndarray) -> Reference:
    """The closed form of the torque-free body (rbcheck.closed_forms.free_asymmetric, Jacobi elliptic
    functions) from w0 (rad/s, body frame) at the grid (s). Its own error: the larger of
    ε·|ω|·T (the rotation angle |ω| T, rad, in double precision) and the change of its end
    state when one component of w0 moves by ε|w0| (the problem's conditioning: no method
    that rounds its start state does better)."""
    I = np.diag(np.asarray(scene.inertia, dtype=float))
    q0 = np.asarray(scene.q0, float)
    w, q = free_asymmetric.solve(I, w0, q0, grid)
    omega = float(np.max(np.abs(w)))
    ref = Reference(np.asarray(grid, float), w, q, "closed form rbcheck.closed_forms.free_asymmetric", 0.0, omega, 0.0)
    floor = EPS * float(np.linalg.norm(w0)) * float(grid[-1])
    for k in range(3):
        w1 = np.array(w0, float)
        w1[k] += EPS * float(np.linalg.norm(w0))
        wp, qp = free_asymmetric.solve(I, w1, q0, grid[-1:])
        floor = max(floor, errors(wp, qp, ref)[2])
    ref.floor = floor
    return ref


def fast_spin(fmu_path: Path, cfg: Config, progress: tqdm[Any] | None) -> list[DefaultRun]:
    """cfg.spin_scene's body (torque-free, three distinct moments) spun at each rate of
    cfg.spin_rates (rad/s) along each direction of cfg.spin_bodies, communication step
    cfg.spin_step (s) for cfg.spin_T (s): at the FMU's defaults and with rk8 at
    DEFAULT_TOLERANCE."""
    sc = load_scene(cfg.spin_scene)
    if not sc.torque_free:
        raise ValueError(f"fast-spin scene {sc.name} must be torque-free (its closed form is the reference)")
    grid = comm_grid(sc, cfg.spin_T, cfg.spin_step)
    out: list[DefaultRun] = []
    drv = ControlDriver(fmu_path, sc)
    try:
        for body, direction in cfg.spin_bodies.items():
            d = np.asarray(direction, float)
            for W in cfg.spin_rates:
                w0 = W * d / float(np.max(np.abs(d)))
                case = f"{body}, ω0 = {W:.0e} rad/s"
                show(progress, f"fast spin: {case}")
                ref = spin_reference(sc, w0, grid)
                drv.start_values = {f"w_body[{k + 1}]": float(w0[k]) for k in range(3)}
                out += settings_runs(drv, sc, case, grid, ref, cfg)
                advance(progress, f"fast spin: {case}")
    finally:
        drv.close()
    return out


def settings_runs(
    drv: ControlDriver, sc: Scene, case: str, grid: np.ndarray, ref: Reference, cfg: Config
) -> list[DefaultRun]:
    """The defaults of the FMU (method, tolerance, h_max as shipped) and, where the default
    method is not rk8 at DEFAULT_TOLERANCE already, rk8 at DEFAULT_TOLERANCE."""
    T, step = float(grid[-1]), float(grid[1] - grid[0])
    runs = []
    drv.defaults = True
    # not set in the FMU at its defaults: the tolerance the shipped settings run with, for
    # the point's record (0: fixed steps)
    drv.tolerance = sc.tolerance if error_controlled(sc.method) else 0.0
    p = drv.measure(sc.method, sc.h_max, grid, ref, cfg.max_repeats)
    runs.append(
        DefaultRun(case, f"defaults ({sc.method})", T, step, ref.source, ref.floor, ref.omega_scale, p, defaults=True)
    )
    drv.defaults = False
    if "rk8" in drv.method_values and not (sc.method == "rk8" and sc.tolerance == DEFAULT_TOLERANCE and sc.h_max == 0):
        drv.tolerance = DEFAULT_TOLERANCE
        p = drv.measure("rk8", 0.0, grid, ref, cfg.max_repeats)
        runs.append(
            DefaultRun(
                case, f"rk8, tolerance {DEFAULT_TOLERANCE:g}", T, step, ref.source, ref.floor, ref.omega_scale, p
            )
        )
    return runs


def default_scene(name: str, fmu_path: Path, cfg: Config, progress: tqdm[Any] | None) -> list[DefaultRun]:
    """Scene `name` as shipped: its communication step, its stop time (or
    cfg.tol_stop_time[name] s where shorter), its default settings, against the report's
    reference (references.make_reference) on the communication grid: the inputs are held
    at their mean over each communication step on both sides."""
    sc = load_scene(name)
    T = min(float(sc.stop_time), cfg.tol_stop_time.get(name, math.inf))
    grid = comm_grid(sc, T, float(sc.step))
    show(progress, f"defaults {name}: reference")
    ref = make_reference(sc, grid)
    drv = ControlDriver(fmu_path, sc)
    try:
        runs = settings_runs(drv, sc, name, grid, ref, cfg)
    finally:
        drv.close()
    advance(progress, f"defaults {name}")
    return runs
