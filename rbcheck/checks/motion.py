r"""Checks of the scenes whose reference point moves: thrown racket, spacecraft thruster, top on a shaker.

Registered with ``@scene_check`` for ``rbfmu check`` (docs/theory.md §7). Each compares
the FMU with Exudyn (:mod:`rbcheck.exudyn.motion`) and the closed forms of
:mod:`rbcheck.closed_forms.free_flight`, and measures the exact balances of
:mod:`rbcheck.checks.balances`. Units SI; ``w`` body angular velocity [rad/s], ``q``
unit quaternion (w, x, y, z) body -> world, positions, velocities, forces in the world
frame. The FMU vs Exudyn trajectories (with x_cm), the closed-form trajectory (the
parabola) and the drifts come from the generic checks.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from modelsrc.scene import Scene

from ..closed_forms import free_asymmetric
from ..closed_forms.free_flight import (
    accelerating_pivot_top,
    harmonic_motion,
    held_pivot_motion,
    parabola,
    shaker_position_bound,
)
from ..exudyn.motion import simulate_motion
from ..numerics.rotation_np import quat_to_matrix, rotation_angle_between
from .balances import held_run
from .bounds import allowed
from .common import exudyn_run, method_codes, run
from .feature_checks import halved_balance_rows
from .free_body import tennis_racket
from .registry import CheckOutput, Row, final_rows, horizon, scene_check

# the tennis-racket exponent's fit is biased by < 1e-4 relative (the growth's nonlinear onset;
# the integrators add ~(h w)^4 ~ 1e-12, tests/checks/test_cross_check.py): held to ten times that
LAMBDA_TOL = 10 * 1e-4

__all__ = ["LAMBDA_TOL", "constant_pivot_acceleration", "pivot_force_newton", "point_rows"]

NAN = float("nan")
# constant pivot accelerations (m/s², world) of the equivalence check: vertical, and slanted
CONSTANT_PIVOT_ACCELERATIONS = ((0.0, 0.0, 3.0), (2.0, -1.0, 4.0))


def point_rows(r_fmu, e: dict, scene: Scene, stop_time: float, origin: str = "x_cm") -> list[Row]:
    """The sensor point against the moving-origin formulas v = v_B + ω × r and
    a = a_B + ω̇ × r + ω × (ω × r) (docs/theory.md §7.2): the FMU's own outputs (judged: an
    identity of its outputs, held to the FMU's bound at the size of the velocity,
    rbcheck.checks.bounds), and the distance of the FMU's body point from Exudyn's (the FMU
    column; the trajectories themselves are judged by the FMU-vs-Exudyn comparison)."""
    rf = r_fmu.vector("sensor_r") - r_fmu.vector(origin)
    vf = r_fmu.vector("v_cm") + np.cross(r_fmu.vector("w_world"), rf)
    re = e["sensor_r"] - e[origin]
    ve = e["v_cm"] + np.cross(e["w_world"], re)
    v_size = float(np.max(np.abs(r_fmu.vector("sensor_v"))))
    rows = [
        Row("max_t |sensor_v - (v_cm + w x r)|", "m/s", float(np.max(np.abs(r_fmu.vector("sensor_v") - vf))),
            float(np.max(np.abs(e["sensor_v"] - ve))), 0.0, allowed(scene, stop_time, v_size)),
        Row("max_t |sensor_v FMU - Exudyn body point|", "m/s",
            float(np.max(np.abs(r_fmu.vector("sensor_v") - e["sensor_v"]))), NAN, 0.0),
    ]  # fmt: skip
    if "sensor_a" in e:
        da = np.abs(r_fmu.vector("sensor_a")[1:] - e["sensor_a"][1:])  # Exudyn's accelerations start after a step
        rows.append(Row("max_t>0 |sensor_a FMU - Exudyn body point|", "m/s^2", float(np.max(da)), NAN, 0.0))
    return rows


def _exact_free_rows(fmu_path: Path, sc: Scene) -> list[Row]:
    """exact_free at a communication step of a quarter of the flight: the parabola and
    the torque-free closed form still hold (docs/theory.md §7.4)."""
    codes = method_codes(fmu_path)
    if "exact_free" not in codes:
        return []
    H = sc.stop_time / 4
    r = run(fmu_path, sc, step=H, start_values={"method": codes["exact_free"], "tolerance": 0.0, "h_max": 10.0 * H})
    x, _ = parabola(sc.x0, sc.v0, sc.g, r.time)
    w, q = free_asymmetric.solve(np.diag(sc.inertia), sc.w0, sc.q0, r.time)
    dx = float(np.max(np.abs(r.vector("x_cm") - x)))
    dw = float(np.max(np.abs(r.vector("w_body") - w)))
    ang = float(np.max(rotation_angle_between(quat_to_matrix(r.vector("q")), quat_to_matrix(q))))
    return [
        Row(f"exact_free, H = {H:g} s: max |x_cm - parabola|", "m", dx, NAN, 0.0),
        Row(f"exact_free, H = {H:g} s: max |w - w_closed|", "rad/s", dw, NAN, 0.0),
        Row(f"exact_free, H = {H:g} s: max attitude error", "rad", ang, NAN, 0.0),
    ]


@scene_check("thrown_racket")
def thrown_racket(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Tennis-racket growth rate in flight, exact_free at a large step, the head's
    velocity from the moving origin, and the balances (docs/theory.md §2.3, §7)."""
    k = int(np.argmax(np.abs(sc.w0)))
    tr = tennis_racket(fmu_path, sc, spin=float(abs(sc.w0[k])), delta=1e-6)
    fit_e = tr.fit_exudyn.rate if tr.fit_exudyn is not None else NAN
    rows = [
        Row(f"tennis-racket lambda, axis {tr.intermediate_axis + 1}", "1/s", tr.fit_fmu.rate, fit_e, tr.lam_formula,
            LAMBDA_TOL * abs(tr.lam_formula))
    ]  # fmt: skip
    rows += _exact_free_rows(fmu_path, sc)
    T = horizon(sc, quick)
    r, e = run(fmu_path, sc, stop_time=T), exudyn_run(sc, stop_time=T)
    rows += point_rows(r, e, sc, T)
    rows += halved_balance_rows(fmu_path, sc, T)  # at H and H/2, judged there (Simpson's 16-fold fall)
    note = "lambda: tennis_racket_exponent; balances: rbcheck.checks.balances (Simpson per step)"
    return CheckOutput(rows, note, {"tennis_racket": tr})


@scene_check("spacecraft_thruster")
def spacecraft_thruster(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Final state of the fired spacecraft, FMU vs Exudyn; the work, momentum and
    angular-momentum balances of the off-centre thruster; the antenna tip (§7.1, §7.2)."""
    T = horizon(sc, quick)
    r, e = run(fmu_path, sc, stop_time=T), exudyn_run(sc, stop_time=T)
    rows = final_rows(r, e)
    for key, unit in (("x_cm", "m"), ("p", "N s"), ("L_world", "N m s")):
        for j in range(3):
            rows.append(Row(f"{key}[{j + 1}](T)", unit, float(r.vector(key)[-1, j]), float(e[key][-1, j])))
    rows.append(Row("E_kin(T)", "J", float(r.values["E_kin"][-1]), float(e["E_kin"][-1])))
    rows += point_rows(r, e, sc, T)
    rows += halved_balance_rows(fmu_path, sc, T, step=sc.fixed_step)  # Simpson on steps of fixed_step and half
    return CheckOutput(rows, "no closed form (a thrust turning with the body); balances: rbcheck.checks.balances")


def constant_pivot_acceleration(
    fmu_path: Path, sc: Scene, a: tuple[float, float, float], stop_time: float
) -> list[Row]:
    """The moving-pivot top with a constant pivot acceleration a (m/s², world) against
    the Lagrange top in gravity g − a (rbcheck.closed_forms.free_flight.accelerating_pivot_top): the
    FMU and Exudyn's spherical joint to a prescribed shaker (docs/theory.md §7.3)."""
    sc_a = dataclasses.replace(sc, inputs={"a_pivot": np.array(a)}, x0=np.zeros(3), v0=np.zeros(3))
    start = {f"x_pivot[{j}]": 0.0 for j in (1, 2, 3)} | {f"v_pivot[{j}]": 0.0 for j in (1, 2, 3)}
    r = run(fmu_path, sc_a, stop_time=stop_time, start_values=start)
    e = exudyn_run(sc_a, stop_time=stop_time, h=0.25 * sc.fixed_step)
    w, q = accelerating_pivot_top(sc.inertia, sc.mass, sc.r_cm, sc.g, a, sc.q0, sc.w0, r.time)
    Rq = quat_to_matrix(q)

    def dev(y: dict) -> tuple[float, float]:
        return float(np.max(np.abs(y["w_body"] - w))), float(np.max(rotation_angle_between(quat_to_matrix(y["q"]), Rq)))

    fw, fa = dev({"w_body": r.vector("w_body"), "q": r.vector("q")})
    ew, ea = dev(e)
    tag = f"a_pivot ({a[0]:g},{a[1]:g},{a[2]:g})"
    # tolerances (rbcheck.checks.bounds): the closed-form rate's size, 2 for the angle
    W = float(np.max(np.abs(w)))
    return [
        Row(f"{tag}: max |w - w_top(g - a)|", "rad/s", fw, ew, 0.0, allowed(sc, stop_time, W)),
        Row(f"{tag}: max attitude to top(g - a)", "rad", fa, ea, 0.0, allowed(sc, stop_time, 2.0)),
    ]


def pivot_force_newton(fmu_path: Path, sc: Scene, window: float) -> tuple[float, float, float]:
    """f_pivot against Newton's law for Exudyn's centre of mass over [0, window] s, steps
    of h_max: the FMU's mean of f_pivot over each step (Simpson on the held run) vs
    M (Δv_cm/H − g) from Exudyn's velocities (trapezoidal rule, internal step H/4).
    Returns (max difference N, Exudyn's Richardson estimate of its own error N (run at
    H/8, order 2), largest |f_pivot| N)."""
    H = sc.fixed_step
    hr = held_run(fmu_path, sc, window, step=H)
    f_mean = (hr.start["f_pivot"] + 4.0 * hr.mid["f_pivot"] + hr.end["f_pivot"]) / 6.0
    v_e = [simulate_motion(sc, stop_time=window, step=H, h=H / k, inputs="hold")["v_cm"] for k in (4, 8)]
    f_e = [sc.mass * (np.diff(v, axis=0) / H - sc.g) for v in v_e]
    est = float(np.max(np.abs(f_e[0] - f_e[1]))) / (1 - 2.0**-2)
    return float(np.max(np.abs(f_mean - f_e[0]))), est, float(np.max(np.abs(f_mean)))


@scene_check("top_on_shaker", quick_stop_time=0.5)
def top_on_shaker(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Constant pivot accelerations against the heavy-top closed form in g − a; the
    shaker's pivot against its held motion and −A cos ωt; f_pivot against Newton's law
    for Exudyn's centre of mass; the work balance of the pivot force (§7.3)."""
    T = horizon(sc, quick)
    rows: list[Row] = []
    for a in CONSTANT_PIVOT_ACCELERATIONS:
        rows += constant_pivot_acceleration(fmu_path, sc, a, min(T, 0.5))
    # continuous inputs (fmu.drive.run, rbcheck.exudyn.motion): both follow the shaker's closed form;
    # the FMU held over each step (as an importer without intermediate update) follows the
    # held double integral, within the bound of the closed form
    r, e = run(fmu_path, sc, stop_time=T), exudyn_run(sc, stop_time=T, h=0.25 * sc.fixed_step)
    r_held = run(fmu_path, sc, stop_time=T, inputs="hold")
    acc = np.array([sc.input_mean("a_pivot", t0, t1) for t0, t1 in zip(r.time[:-1], r.time[1:])])
    x_held, _ = held_pivot_motion(r.time, acc, sc.x0, sc.v0)
    # (row, unit, pivot variable, reference motion, what the reference leaves out (m), with Exudyn):
    # the held run has no Exudyn counterpart (Exudyn follows the continuous shaker), the continuous one has
    gaps = [("held inputs: max_t |x_pivot - held double integral|", "m", "x_pivot", x_held, 0.0, False)]
    spec = sc.inputs.get("a_pivot")
    if spec is not None and hasattr(spec, "omega"):
        x_h, v_h = harmonic_motion(spec.amplitude, spec.omega, spec.phase, sc.x0, sc.v0, r.time)
        # the held run against the continuous shaker: what holding the input over a step adds
        hold = shaker_position_bound(float(np.max(np.abs(spec.amplitude))), spec.omega, sc.step)
        gaps += [
            ("held inputs: max_t |x_pivot - shaker position| (within the hold's bound)", "m", "x_pivot", x_h, hold,
             False),
            ("max_t |v_pivot - shaker velocity|", "m/s", "v_pivot", v_h, 0.0, True),
            ("max_t |x_pivot - shaker position|", "m", "x_pivot", x_h, 0.0, True),
        ]  # fmt: skip
    for label, unit, name, ref, left_out, continuous in gaps:
        fmu_run = r if continuous else r_held
        fmu_gap = float(np.max(np.abs(fmu_run.vector(name) - ref)))
        exudyn_gap = float(np.max(np.abs(e[name] - ref))) if continuous else NAN
        # judged at the size of the motion, plus what the reference leaves out (shaker_position_bound,
        # H² A ω²/6 with 10 % margin, for the held run against the continuous shaker)
        rows.append(Row(label, unit, fmu_gap, exudyn_gap, 0.0, allowed(sc, T, float(np.max(np.abs(ref)))) + left_out))
    diff, est, scale = pivot_force_newton(fmu_path, sc, min(T, 0.05))
    rows.append(Row("max |f_pivot - M (dv_cm/dt - g)|, Exudyn v", "N", diff, NAN, 0.0,
                    allowed(sc, min(T, 0.05), scale, reference=est)))  # fmt: skip
    rows.append(Row("  Exudyn's error estimate of M dv_cm/dt", "N", NAN, est))
    rows.append(Row("max |f_pivot| (same window)", "N", scale, NAN))
    rows += halved_balance_rows(fmu_path, sc, T)  # at H and H/2, judged there (Simpson's 16-fold fall)
    note = (
        "closed forms: rbcheck.closed_forms.free_flight (top in g - a, held pivot motion, shaker: v = A w "
        "sin(w t) exact, "
        "x = -A cos(w t) within the bound); Exudyn: spherical joint to a prescribed shaker (trapezoidal)"
    )
    return CheckOutput(rows, note)
