r"""The checks of the rotors and the scipy reference of any scene, each row with the tolerance it is held to.

Run by ``rbfmu check`` for every scene with rotors that has no check of its own (the table
of rbcheck.checks.feature_table says which feature gets which check):

* the total angular momentum L_world is constant when only the motors act (their torques
  are internal: +u g on the rotor, −u g on the body, docs/theory.md §8.1);
* the work balance E(t) − E(0) = ∫ Σ u Ω dt (§8.2), by Simpson's rule per communication
  step (rbcheck.checks.balances), at the scene's step H and at H/2 (`halved_balance_rows`,
  run by the generic check "input balances" for every scene whose inputs do work);
* the jointed Exudyn gyrostat (rbcheck.exudyn.rotors: each rotor a body on a revolute joint),
  Richardson-extrapolated from its steps h and h/2, over a short horizon;
* the scipy reference (rbcheck.baselines: the equations written again in numpy, DOP853 at
  rtol 1e-13) of any scene with rotors, an orbit or a central field, over the scene's run.

Tolerances. The FMU holds a relative error per second of simulated time of ``tolerance``
(docs/theory.md §5.4): over a horizon T a quantity of size S may be off by about
tolerance·T·S; the rows allow ten times that, ``FMU_MARGIN``, plus a round-off floor of
``ROUND_OFF`` S. A reference's own error is estimated from a second run (scipy at rtol
1e-12, Exudyn at h/2) and allowed three times over (the estimates are good to a factor ~2).
A scene with fixed steps (tolerance 0) has no a-priori bound: its rows are shown without a
verdict. Units SI.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fmu.drive.run import RunResult
from modelsrc.methods import METHODS
from modelsrc.scene import Scene

from ..baselines.gyrostat import covers as scipy_covers_rotors
from ..baselines.motion import integrate
from ..exudyn.rotors import covers as exudyn_covers
from ..exudyn.rotors import simulate_gyrostat
from .balances import balances, held_run
from .common import NotApplicable, run
from .registry import GenericOutcome, Row, horizon
from .richardson import richardson_agreement

__all__ = [
    "EXUDYN_HORIZON",
    "FMU_MARGIN",
    "ROUND_OFF",
    "aligned",
    "fine_run",
    "fmu_bound",
    "halved_balance_rows",
    "needed",
    "rotor_exudyn_check",
    "rotor_momentum_check",
    "scipy_reference_check",
]

NAN = float("nan")
FMU_MARGIN = 10.0  # the allowed error: FMU_MARGIN x tolerance x T of a quantity's size
ROUND_OFF = 1e-12  # relative round-off floor (1e-16 per operation over ~1e4 steps)
FINE = 100.0  # the FMU's error estimate: a run at tolerance / FINE
# s: horizon of the Exudyn gyrostat runs (its implicit trapezoidal rule costs ~20-60 µs a step:
# 2 s at h = 1e-3 and 5e-4 s is 6000 steps, a few seconds)
EXUDYN_HORIZON = 2.0
EXUDYN_STEPS = (1e-3, 5e-4)


def fmu_bound(scene: Scene, stop_time: float) -> float:
    """Relative error [-] the FMU's error control allows over stop_time [s]: FMU_MARGIN x tolerance
    x T + ROUND_OFF; nan for fixed steps (tolerance 0: no a-priori bound)."""
    if scene.tolerance <= 0.0:
        return NAN
    return FMU_MARGIN * scene.tolerance * stop_time + ROUND_OFF


def fine_run(fmu_path: Path, scene: Scene, stop_time: float) -> tuple[RunResult, float]:
    """The FMU's run over stop_time [s] with a tighter setting, and the factor that turns the
    difference to it into an error estimate of the scene's run: tolerance / FINE at error
    control (factor 1: the fine run's error is 1/FINE of the other's), h_max / 2 at fixed steps
    (Richardson: 1 / (1 − 2^-p), p the order of the scene's method)."""
    if scene.tolerance > 0.0:
        return run(fmu_path, scene, stop_time=stop_time, start_values={"tolerance": scene.tolerance / FINE}), 1.0
    p = METHODS[scene.method].order
    return run(fmu_path, scene, stop_time=stop_time, start_values={"h_max": 0.5 * scene.fixed_step}), 1 / (1 - 2.0**-p)


def needed(r: RunResult, *names: str) -> None:
    """ValueError naming the outputs a check needs that the FMU's run does not have."""
    missing = [n for n in names if n not in r.values and f"{n}[1]" not in r.values]
    if missing:
        raise ValueError(f"this FMU lacks the outputs {', '.join(missing)}; build it with them in the scene's outputs")


def _external_torques(scene: Scene) -> list[str]:
    """What puts a torque on the whole body about its centre of mass besides the motors."""
    out = sorted(scene.features - {"translation", "gravity"})
    if scene.has("gravity") and not scene.has("translation"):
        out.append("gravity about a pivot")
    out += [f"force point {n}" for n in scene.force_points]
    out += [f"propeller {n}" for n, r in scene.rotors.items() if r.propeller]
    return out


def rotor_momentum_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """max_t |L_world − L_world(0)| / max_t |L_world| on the scene's own run (docs/theory.md §8.1:
    the motor torques are internal, so L_world is constant whatever u)."""
    ext = _external_torques(scene)
    if ext:
        raise NotApplicable(f"external torques act ({', '.join(ext)}), so the total angular momentum is not conserved")
    T = horizon(scene, quick)
    r = run(fmu_path, scene, stop_time=T)
    needed(r, "L_world")
    L = r.vector("L_world")
    scale = float(np.max(np.linalg.norm(L, axis=1)))
    if scale == 0.0:
        raise NotApplicable("the total angular momentum is 0 throughout (nothing turns): nothing to measure")
    rel = float(np.max(np.linalg.norm(L - L[0], axis=1))) / scale
    row = Row("rotors: max|L_world - L_world(0)| / max|L_world|", "-", rel, NAN, 0.0, fmu_bound(scene, T))
    return GenericOutcome(rows=[row], note="L_world: conserved under motor torques (docs/theory.md §8.1)")


def halved_balance_rows(
    fmu_path: Path, scene: Scene, stop_time: float, prefix: str = "", step: float | None = None
) -> list[Row]:
    """The balances of rbcheck.checks.balances on held runs at the scene's step H (shown) and at
    H/2 (judged); the shipped free-flight and shaker scenes' checks (rbcheck.checks.motion) use
    them as the generic check does.

    Simpson's rule per step errs by O(H⁵) a step, so a residual of the quadrature falls
    16-fold at H/2; the FMU's own error does not fall. The residual at H/2 may be the larger
    of 1/8 of the one at H and the FMU's bound (`fmu_bound`) on the balance's size (the
    largest energy and work; momentum and impulse; angular momentum and its impulse; the
    pivot force). A modelling error (a missing power or torque term) falls with neither. step:
    H (s; default the scene's communication step)."""
    H = scene.step if step is None else step
    b0, b1 = (balances(scene, held_run(fmu_path, scene, stop_time, step=h)) for h in (H, 0.5 * H))
    bound = fmu_bound(scene, stop_time)
    H2 = f"at H/2 = {0.5 * H:g} s"
    rows = []
    for name, unit, r0, r1, scale in (
        ("work balance |dE_total - int P dt|", "J", b0.work, b1.work, b1.E_scale + abs(b1.work_done)),
        ("momentum balance |dp - int (F + M g) dt|", "N s", b0.momentum, b1.momentum, b1.p_scale),
        ("ang. momentum balance |dL - int tau dt|", "N m s", b0.angular_momentum, b1.angular_momentum, b1.L_scale),
        ("pivot force |f_pivot - M (a_cm - g)|", "N", b0.pivot_force, b1.pivot_force, b1.f_scale),
    ):
        if not np.isfinite(r0):
            continue
        tol = max(r0 / 8.0, bound * scale) if np.isfinite(bound) else NAN
        rows.append(Row(f"{prefix}{name}", unit, r0, NAN, 0.0))
        rows.append(Row(f"{prefix}{name}, {H2}", unit, r1, NAN, 0.0, tol))
    rows.append(Row(f"{prefix}work done by the inputs, int P dt", "J", b1.work_done, NAN))
    return rows


def rotor_exudyn_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """The FMU against the jointed Exudyn gyrostat (rbcheck.exudyn.rotors) over min(T,
    EXUDYN_HORIZON), Richardson from h = 1e-3 and 5e-4 s (trapezoidal rule, order 2): q, ω and each
    rotor's Ω. Allowed: 3 x (Exudyn's own estimate |x(h/2) − x(h)| + the FMU's, `fine_run`)
    plus 1e-12 of the quantity's size (the extrapolated value errs by O(h³), far below the estimate)."""
    if scene.has("orbit"):
        raise NotApplicable(
            "the Exudyn gyrostat has no orbit, and a wheel's spin needs its implicit steps below 1e-3 s (with the "
            "gravity-gradient torque as a hub load and a wheel at 400 rad/s, h = 1e-3 s estimated its own error at "
            "3e-3 in q over 2 s: no check); the scipy gyrostat is the reference in an orbit"
        )
    why = exudyn_covers(scene)
    if why is not None:
        raise NotApplicable(f"the Exudyn gyrostat (rbcheck.exudyn.rotors) does not cover it: {why}")
    T = min(horizon(scene, quick), EXUDYN_HORIZON)
    r = run(fmu_path, scene, stop_time=T)
    keys = ["q", "w_body"] + [f"Omega_{n}" for n in scene.rotors]
    fmu = {k: (r.vector(k) if k in ("q", "w_body") else r.values[k]) for k in keys}
    coarse, fine = (simulate_gyrostat(scene, stop_time=T, h=h) for h in EXUDYN_STEPS)
    ag = richardson_agreement(fmu, coarse, fine, keys)
    tight, factor = fine_run(fmu_path, scene, T)
    own = {k: (tight.vector(k) if k in ("q", "w_body") else tight.values[k]) for k in keys}
    e_fmu = {k: factor * float(np.max(np.abs(own[k] - fmu[k]))) for k in keys}

    def tol(k: str) -> float:
        return 3.0 * (ag.estimate[k] + e_fmu[k]) + ROUND_OFF * float(np.max(np.abs(fmu[k])))

    rows = [
        Row(f"rotors: max|{k} - {k}_Exudyn| over {T:g} s", unit, ag.diff[k], ag.estimate[k], 0.0, tol(k))
        for k, unit in (("q", "-"), ("w_body", "rad/s"))
    ]
    wheels = [k for k in keys if k.startswith("Omega_")]
    worst = max(wheels, key=lambda k: ag.diff[k] - tol(k))
    rows.append(
        Row(
            f"rotors: max|Omega - Omega_Exudyn| ({worst})", "rad/s", ag.diff[worst], ag.estimate[worst], 0.0, tol(worst)
        )
    )
    note = (
        f"Exudyn: each rotor on a revolute joint (rbcheck.exudyn.rotors), Richardson from h = {EXUDYN_STEPS[0]:g}, "
        f"{EXUDYN_STEPS[1]:g} s; its column: its own error estimate |x(h) - x(h/2)|"
    )
    return GenericOutcome(rows=rows, note=note)


def aligned(q: NDArray, ref: NDArray) -> NDArray:
    """q with each row's sign chosen to match ref's (q and −q are one rotation)."""
    return q * np.where(np.sum(q * ref, axis=1) < 0.0, -1.0, 1.0)[:, None]


def scipy_reference_check(fmu_path: Path, scene: Scene, quick: bool) -> GenericOutcome:
    """The FMU's run against the scipy reference of rbcheck.baselines (the scene's equations
    written again in numpy, DOP853 at rtol 1e-13; its own error from a run at rtol 1e-12) over
    the scene's horizon: q, ω, the rotors' Ω, the centre of mass."""
    if scene.rotors and not scipy_covers_rotors(scene):
        raise NotApplicable("the scipy gyrostat (rbcheck.baselines.gyrostat) does not cover these rotors")
    if scene.has("orbit") and np.count_nonzero(scene.inertia - np.diag(np.diag(scene.inertia))):
        raise NotApplicable("the scipy orbit reference needs the principal axes along the body axes")
    T = horizon(scene, quick)
    r = run(fmu_path, scene, stop_time=T)
    fine, factor = fine_run(fmu_path, scene, T)
    ref, est = (integrate(scene, r.time, rtol=tol) for tol in (1e-13, 1e-12))

    def outputs(x: RunResult) -> dict[str, NDArray]:
        out = {"q": aligned(x.vector("q"), ref.q), "w_body": x.vector("w_body")}
        if scene.rotors:
            out["Omega"] = np.column_stack([x.values[f"Omega_{n}"] for n in ref.extra["rotors"]])
        if "x_cm" in ref.extra:
            out["x_cm"] = x.vector("x_cm")
        return out

    refs = {"q": (ref.q, aligned(est.q, ref.q)), "w_body": (ref.w_body, est.w_body)}
    if scene.rotors:
        refs["Omega"] = (ref.extra["Omega"], est.extra["Omega"])
    if "x_cm" in ref.extra:
        refs["x_cm"] = (ref.extra["x_cm"], est.extra["x_cm"])
    units = {"q": "-", "w_body": "rad/s", "Omega": "rad/s", "x_cm": "m"}
    f, f_fine = outputs(r), outputs(fine)
    rows = []
    for name, (a, b) in refs.items():
        d = float(np.max(np.abs(f[name] - a)))
        e_fmu = factor * float(np.max(np.abs(f[name] - f_fine[name])))
        e_ref = float(np.max(np.abs(b - a)))
        tol = 3.0 * (e_fmu + e_ref) + ROUND_OFF * float(np.max(np.abs(a)))
        rows.append(Row(f"max|{name} - {name}_scipy| over {T:g} s", units[name], d, NAN, 0.0, tol))
    note = (
        "scipy: rbcheck.baselines (numpy equations, DOP853 rtol 1e-13); allowed: 3 x (the FMU's error estimate "
        "from a run at tolerance/100 + scipy's from rtol 1e-12) + 1e-12 of the size"
    )
    return GenericOutcome(rows=rows, note=note)
