r"""The scene-specific checks of ``rbfmu check``, one per shipped scene, registered by name.

Each is a function ``(fmu_path, scene, quick) -> CheckOutput`` with the rows only that
scene has; the closed-form trajectory, FMU-vs-Exudyn comparison and drift rows every
scene gets come from :mod:`rbcheck.checks.generic`. ``quick_stop_time`` [s] caps the
horizon under ``--quick``. Units SI; ``w`` body angular velocity [rad/s], ``q`` unit
quaternion (w, x, y, z) body -> world, world z up.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from modelsrc.scene import Scene

from ..closed_forms import heavy_top as ht
from ..closed_forms.frame_kinematics import arm_wrist
from ..closed_forms.skewed_bar import bearing_torque
from ..exudyn.skewed_bar import exudyn_revolute
from ..numerics.rotation_np import quat_to_matrix
from .bounds import allowed, vertex_error
from .common import exudyn_run, run
from .feature_checks import halved_balance_rows
from .free_body import symmetric_top_rates, tennis_racket
from .gyrostat import GROWTH_EPS, exudyn_agreement, growth, momentum_conservation, motor_balance, nutation, spin_setup
from .motion import LAMBDA_TOL
from .registry import CheckOutput, Row, final_rows, horizon, scene_check
from .sleeping_top import GROWTH_FIT_BIAS, friction_onset, sleeping_threshold, vertical_growth
from .tops import fast_top_scaling, heavy_top_nutation, top_params

NAN = float("nan")


@scene_check("free_asymmetric", quick_stop_time=15.0)
def free_asymmetric(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Tennis racket: growth rate about the intermediate axis, bounded extreme axes (§2.3)."""
    tr = tennis_racket(fmu_path, sc)
    k = tr.intermediate_axis
    fit_e = tr.fit_exudyn.rate if tr.fit_exudyn is not None else NAN
    rows = [
        Row(f"tennis-racket lambda, axis {k + 1}, delta {tr.delta:g}", "1/s", tr.fit_fmu.rate, fit_e, tr.lam_formula,
            LAMBDA_TOL * abs(tr.lam_formula))
    ]  # fmt: skip
    for a in range(3):
        if a != k:
            rows.append(
                Row(f"max|dw|/|dw0|, spin about axis {a + 1}", "-", tr.growth_fmu[a], tr.growth_exudyn[a], tr.bound[a])
            )
    rows.append(Row(f"max|dw|/|dw0|, spin about axis {k + 1}", "-", tr.growth_fmu[k], tr.growth_exudyn[k]))
    return CheckOutput(rows, "lambda: tennis_racket_exponent", {"tennis_racket": tr})


@scene_check("symmetric_free", quick_stop_time=5.0)
def symmetric_free(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Body precession rate Omega and coning rate |L|/I1 of the torque-free symmetric top."""
    T = horizon(sc, quick)
    st = symmetric_top_rates(fmu_path, sc, stop_time=T)
    rows = [  # rbcheck.checks.bounds: at the size of each rate
        Row("Omega (w1 + i w2 ~ e^{-i Omega t})", "rad/s", st.omega_fmu, st.omega_exudyn, st.omega_formula,
            allowed(sc, T, st.omega_formula)),
        Row("coning rate of e3 about L", "rad/s", st.coning_fmu, st.coning_exudyn, st.coning_formula,
            allowed(sc, T, st.coning_formula)),
    ]  # fmt: skip
    return CheckOutput(rows, "Omega, coning: rbcheck.closed_forms.free_symmetric formulas", {"symmetric_top": st})


@scene_check("heavy_top", quick_stop_time=1.0)
def heavy_top(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Nutation bounds, period, precession against the elliptic closed form; fast-top ladder."""
    P = top_params(sc)
    top = ht.HeavyTop(P, ht.init_from_state(sc.q0, sc.w0))
    period = top.period
    periods = min(8.2, horizon(sc, quick) / period)
    hr = heavy_top_nutation(fmu_path, sc, periods=periods)
    m_e = hr.exudyn
    # rbcheck.checks.bounds over the run of `periods` nutation periods: the period and the mean
    # precession (from crossings) at their size, u = cos(theta) at 1; the extrema u1, u2 come from a
    # parabola through sampled points, whose own error max |u‴| H³ (bounds.vertex_error) adds
    T = periods * period
    u_tol = allowed(sc, T, 1.0) + vertex_error(top.u, period, hr.step)
    rows = [
        Row("nutation u1 = min cos(theta)", "-", hr.fmu.u1, m_e.u1 if m_e else NAN, hr.u1, u_tol),
        Row("nutation u2 = max cos(theta)", "-", hr.fmu.u2, m_e.u2 if m_e else NAN, hr.u2, u_tol),
        Row("nutation period", "s", hr.fmu.period, m_e.period if m_e else NAN, hr.period, allowed(sc, T, hr.period)),
        Row(
            "mean precession rate",
            "rad/s",
            hr.fmu.precession,
            m_e.precession if m_e else NAN,
            hr.precession,
            allowed(sc, T, hr.precession),
        ),
        Row("max_t |u - u_closed|", "-", hr.max_du_fmu, hr.max_du_exudyn, 0.0, allowed(sc, T, 1.0)),
        Row("I1 about the pivot (I1cm + M l^2)", "kg m^2", NAN, NAN, P.I1),
    ]
    ladder = (150.0, 300.0, 600.0, 1200.0) if quick else (150.0, 300.0, 600.0, 1200.0, 2400.0)
    fast = fast_top_scaling(fmu_path, sc, w3_values=ladder)
    note = "nutation, fast top: rbcheck.closed_forms.heavy_top"
    return CheckOutput(rows, note, {"nutation": hr, "fast_top": fast})


@scene_check("sleeping_top", quick_stop_time=8.0)
def sleeping_top(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Sleeping threshold +-2 %, tilt growth below it, and the friction-driven onset (§4.2, §4.3)."""
    P = top_params(sc)
    wc = ht.sleeping_threshold(P.I1, P.I3, P.M, P.g, P.l)
    above = sleeping_threshold(fmu_path, sc, 1.02, periods=4.0 if quick else 10.0)
    below = sleeping_threshold(fmu_path, sc, 0.98, periods=1.0)
    vg = vertical_growth(fmu_path, sc, 0.98)
    on = friction_onset(fmu_path, sc, stop_time=horizon(sc, quick))
    fit_e = vg.fit_exudyn.rate if vg.fit_exudyn is not None else NAN
    # rbcheck.checks.bounds: a tilt errs at most as the attitude angle does (size 2, the angle of
    # the unit quaternion's error), plus the refined maximum's own error (bounds.vertex_error);
    # the fitted growth rate by its window's biases (GROWTH_FIT_BIAS, relative); the crossing time
    # by the rate's error over |dw3/dt| = k w_c (k = c/I3: the scale 1/k) plus the linear
    # interpolation of w3 between samples, H² |d²w3/dt²| / 8 over |dw3/dt|, = H² k / 8
    k = sc.c_friction / P.I3
    rows = [
        Row("sleeping threshold w_c = sqrt(4 M g l I1)/I3", "rad/s", NAN, NAN, wc),
        *(
            Row(
                f"max tilt, w3 = {res.factor:.2f} w_c, {res.stop_time:.1f} s",
                "rad",
                res.max_tilt_fmu,
                res.max_tilt_exudyn,
                res.max_tilt_closed,
                allowed(sc, res.stop_time, 2.0) + res.vertex_error,
            )
            for res in (above, below)
        ),
        Row(
            f"tilt growth rate, w3 = 0.98 w_c, tilt0 {vg.theta0:g}",
            "1/s",
            vg.fit_fmu.rate,
            fit_e,
            vg.lam_formula,
            allowed(sc, vg.stop_time, vg.lam_formula, model=GROWTH_FIT_BIAS),
        ),
        Row(
            "friction: w3 crosses w_c at",
            "s",
            on.t_cross_fmu,
            NAN,
            on.t_cross_formula,
            allowed(sc, on.stop_time, 1.0 / k) + sc.step**2 * k / 8.0,
        ),
        Row(f"friction: tilt reaches {on.band:g} rad at", "s", on.t_onset, on.exudyn_t_onset),
        Row("friction: max tilt while w3 > w_c", "rad", on.max_tilt_before, on.exudyn_max_tilt_before),
        Row("friction: onset delay x lambda(t_onset)", "-", on.delay_growth_times, NAN),
        Row("friction: int lambda dt, crossing->onset", "e-folds", on.efolds, NAN, on.efolds_needed),
    ]
    note = (
        "closed form: rbcheck.closed_forms.heavy_top (elliptic, frictionless +-2 % runs; the FMU's "
        "c_friction is set to 0); last row's closed column = ln(band/max tilt before)"
    )
    return CheckOutput(rows, note, {"above": above, "below": below, "growth": vg, "onset": on})


@scene_check("torque_driven", quick_stop_time=8.0)
def torque_driven(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Final state of the torque-driven body, FMU vs Exudyn (no closed form), and the work
    and angular-momentum balances of its torque tables (rbcheck.checks.balances, at H and
    H/2, judged at H/2 as the generic input balances are)."""
    T = horizon(sc, quick)
    r = run(fmu_path, sc, stop_time=T)
    e = exudyn_run(sc, stop_time=T)
    rows = final_rows(r, e)
    rows.append(Row("E_kin(T)", "J", float(r.values["E_kin"][-1]), float(e["E_kin"][-1])))
    for k in range(3):
        rows.append(Row(f"L_world[{k + 1}](T)", "N m s", float(r.vector("L_world")[-1, k]), float(e["L_world"][-1, k])))
    rows += halved_balance_rows(fmu_path, sc, T)
    return CheckOutput(rows, "no closed form (piecewise-constant torque tables); balances: rbcheck.checks.balances")


@scene_check("skewed_bar")
def skewed_bar(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Bearing torque that holds the prescribed rate (MIT 2.003J) against the formula and
    the reaction of an Exudyn revolute joint, at the scene's and three other angles."""
    I_a, I_t = float(sc.inertia[0, 0]), float(sc.inertia[1, 1])
    theta_dot = float(np.linalg.norm(sc.w0))
    # tolerance (rbcheck.checks.bounds): runs of 1 s; the torque's size ½ |I_t − I_a| θ̇², its
    # largest value over the angles
    tol = allowed(sc, 1.0, 0.5 * abs(I_t - I_a) * theta_dot**2)
    rows = []
    for phi in (float(np.arctan2(-sc.w0[1], sc.w0[0])), 0.0, np.pi / 4, np.pi / 2):
        c, s_ = np.cos(phi / 2), np.sin(phi / 2)
        start = {
            "q[1]": c,
            "q[2]": 0.0,
            "q[3]": 0.0,
            "q[4]": s_,
            "w_body[1]": theta_dot * np.cos(phi),
            "w_body[2]": -theta_dot * np.sin(phi),
            "w_body[3]": 0.0,
        }
        r = run(fmu_path, sc, stop_time=1.0, start_values=start)
        tau = r.vector("tau_bearing")
        ref = bearing_torque(r.time, I_a, I_t, phi, theta_dot)
        ex = exudyn_revolute(I_a, I_t, float(sc.mass), phi, theta_dot, 0.5)
        late = ex["time"] > 0.1  # after generalized-alpha's start-up transient of the multipliers
        ref_ex = bearing_torque(ex["time"][late], I_a, I_t, phi, theta_dot)
        deg = f"{np.degrees(phi):.0f} deg"
        rows.append(
            Row(
                f"max |tau_bearing|, phi = {deg}",
                "N m",
                float(np.max(np.linalg.norm(tau, axis=1))),
                float(np.max(np.linalg.norm(ex["tau_world"][late], axis=1))),
                float(np.max(np.linalg.norm(ref, axis=1))),
                tol,
            )
        )
        rows.append(
            Row(
                f"max_t |tau - tau_formula|, phi = {deg}",
                "N m",
                float(np.max(np.abs(tau - ref))),
                float(np.max(np.abs(ex["tau_world"][late] - ref_ex))),
                0.0,
                tol,
            )
        )
    note = (
        "closed form: -(I_t - I_a) thetadot^2 sin(phi) cos(phi) k_A (rbcheck.closed_forms.skewed_bar); Exudyn: "
        "reaction torque of a revolute joint (generalized-alpha, h = 2^-12 s, t > 0.1 s)"
    )
    return CheckOutput(rows, note)


@scene_check("two_frame_arm")
def two_frame_arm(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """Wrist (sensor) position, velocity, acceleration against the MIT 2.003J handout's
    two-frame formulas (upper arm Omega about the vertical J, forearm omega about i_A)."""
    T = horizon(sc, quick)
    r = run(fmu_path, sc, stop_time=T)
    e = exudyn_run(sc, stop_time=T)
    Rq0 = quat_to_matrix(sc.q0)
    omega_w = Rq0 @ sc.w0  # = Omega J + omega i_A at t = 0
    i_A0 = Rq0[:, 2]
    J = np.array([0.0, 0.0, 1.0])
    Omega = float(omega_w @ J - (omega_w @ i_A0) * (i_A0 @ J)) / float(1 - (i_A0 @ J) ** 2)
    omega = float(omega_w @ i_A0 - Omega * (i_A0 @ J))
    p_body = np.asarray(sc.sensor_point)
    L_arm = float(p_body[2])
    l_fore = float(np.hypot(p_body[0], p_body[1]))
    i_F0 = Rq0 @ np.array([p_body[0], p_body[1], 0.0]) / l_fore
    rows = [
        Row("Omega (upper arm about the vertical)", "rad/s", NAN, NAN, Omega),
        Row("omega (forearm about the upper arm)", "rad/s", NAN, NAN, omega),
    ]
    for key, unit in (("r", "m"), ("v", "m/s"), ("a", "m/s^2")):
        ref_f = arm_wrist(r.time, Omega, omega, L_arm, l_fore, J, i_A0, i_F0)[key]
        ref_e = arm_wrist(e["time"], Omega, omega, L_arm, l_fore, J, i_A0, i_F0)[key]
        first = 1 if key == "a" else 0  # Exudyn has accelerations only after its first step
        rows.append(
            Row(
                f"max_t |wrist {key} - handout formula|",
                unit,
                float(np.max(np.abs(r.vector(f"sensor_{key}") - ref_f))),
                float(np.max(np.abs(e[f"sensor_{key}"][first:] - ref_e[first:]))),
                0.0,
                allowed(sc, T, float(np.max(np.abs(ref_f)))),  # rbcheck.checks.bounds, at the wrist's r, v or a
            )
        )
    note = "wrist: MIT 2.003J arm (rbcheck.closed_forms.frame_kinematics); Exudyn: body outputs at the sensor point"
    return CheckOutput(rows, note)


@scene_check("dual_spin", quick_stop_time=35.0)  # two nutation periods (16.6 s) and a crossing
def dual_spin(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """The gyrostat (docs/theory.md §8): world angular momentum under motor torques, nutation
    frequency and growth rate against the closed forms of §8.3, the jointed Exudyn model."""
    cons = momentum_conservation(fmu_path, sc)
    mb = motor_balance(fmu_path, sc)
    T_nut = horizon(sc, quick)
    nut = nutation(fmu_path, sc, stop_time=T_nut, exudyn=not quick)
    gr = growth(fmu_path, sc)
    # tolerances (rbcheck.checks.bounds): the balance runs last 10 s, the growth run 25 s, the
    # Exudyn runs 2 s; the sizes: the spin rate, the body's and the wheel's momentum, the wheel's
    # rate, the energy the motor changes; the linearised forms are off by O(a²) at the amplitude
    # a/ω_s the runs reach (ε for the nutation, the grown transverse rate for the growth)
    sp = spin_setup(sc)
    w_size, L_size = abs(sp.w_s), abs(float(sp.I[sp.s]) * sp.w_s) + abs(sp.h_w)
    Omega_size = abs(sp.h_w) / sp.J
    grown = (gr.growth_unstable * GROWTH_EPS / w_size) ** 2
    rows = [
        Row("max|L_world - L_world(0)| / |L|, u = 0", "-", cons.rel_drift_free, NAN, 0.0, allowed(sc, 10.0, 1.0)),
        Row("max|L_world - L_world(0)| / |L|, u schedule", "-", cons.rel_drift_driven, NAN, 0.0,
            allowed(sc, 10.0, 1.0)),
        Row("wheel rate change under the u schedule", "rad/s", cons.wheel_rate_change, NAN),
        Row("work balance |dE - int u Omega dt|, u schedule", "J", mb.work, NAN, 0.0,
            allowed(sc, 10.0, mb.work_without_motor)),
        Row("  same without the motor power u Omega (wrong)", "J", mb.work_without_motor, NAN),
        Row("ang. momentum balance |dL_world|, u schedule", "N m s", mb.angular_momentum, NAN, 0.0,
            allowed(sc, 10.0, L_size)),
        Row(f"nutation frequency, eps {nut.eps:g} rad/s", "rad/s", nut.fmu, nut.exudyn, nut.closed,
            allowed(sc, T_nut, nut.closed, model=(nut.eps / w_size) ** 2)),
        Row(f"growth rate, wheel h_w = {gr.h_unstable:g} N m s (unstable)", "1/s", gr.rate_fmu, NAN, gr.rate_closed,
            allowed(sc, 25.0, gr.rate_closed, model=grown)),
        Row("max|w_perp|/eps, unstable wheel", "-", gr.growth_unstable, NAN),
        # shown against the closed form's bound on the transverse rate (at most it), not judged as equal to it
        Row(f"max|w_perp|/eps, scene's wheel h_w = {gr.h_stable:g} N m s", "-", gr.growth_stable, NAN, gr.bound_stable),
    ]  # fmt: skip
    details: dict = {"conservation": cons, "motor_balance": mb, "nutation": nut, "growth": gr}
    for u in (0.0, 2.0):
        ag = exudyn_agreement(fmu_path, sc, u)
        rows.append(Row(f"max|w - w_Exudyn|, u = {u:g} N m (Exudyn Richardson)", "rad/s", ag.dw, ag.est_w, NAN,
                        allowed(sc, 2.0, w_size, reference=ag.est_w)))  # fmt: skip
        rows.append(Row(f"max|Omega - Omega_Exudyn|, u = {u:g} N m", "rad/s", ag.dOmega, ag.est_Omega, NAN,
                        allowed(sc, 2.0, Omega_size, reference=ag.est_Omega)))  # fmt: skip
        details[f"exudyn_u{u:g}"] = ag
    note = (
        "closed forms: rbcheck.closed_forms.dual_spin (gyrostat, linearised); Exudyn: rotor on a revolute joint "
        "(rbcheck.exudyn.rotors), Richardson from h = 2e-4, 1e-4 s; its column in the agreement rows: "
        "Exudyn's own error estimate |x(h) - x(2h)|"
    )
    return CheckOutput(rows, note, details)
