"""The reaction-wheel slew's check: the closed PD loop from fmpy against its exact sampled-data solution.

Runs the scene ``reaction_wheel_slew`` with the PD law of :mod:`rbcheck.closed_forms.slew` as the
importer's input function (u computed at every communication point from the outputs q and
w_body, held over the step) and compares with the exact eigenaxis recursion there
(docs/theory.md §8.4): total world angular momentum (0 from rest), the wheels' momenta
against the body's, the slew angle and the final attitude error; and with the jointed
Exudyn gyrostat (rbcheck.exudyn.rotors) closing the same loop on its own state at the same
sample times (docs/theory.md §8.7). Units SI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fmu.drive.run import RunResult
from modelsrc.scene import Scene

from ..closed_forms.slew import SLEW_GAINS, PDSlew, eigenaxis_reference, slew_law
from ..exudyn.rotors import simulate_gyrostat
from .bounds import allowed
from .common import run
from .registry import CheckOutput, Row, scene_check
from .richardson import Agreement, richardson_agreement

__all__ = ["EXUDYN_STEP", "SLEW_GAINS", "Slew", "exudyn_slew", "slew", "slew_run"]

NAN = float("nan")
# Exudyn's internal steps (s) of the agreement rows, Richardson from h and h/2 (trapezoidal
# rule, order 2), with the check's (quick) and the full horizon. Measured over the 40 s
# slew: max|q − q_R| 7.7e-8 from (1e-3, 5e-4), 9.6e-9 from (5e-4, 2.5e-4) s (the error left
# is O(h³): 8x per halving); 2 and 3.5 s of Exudyn wall time.
EXUDYN_STEP = {True: 1e-3, False: 5e-4}


@dataclass
class Slew:
    """Measured on the closed-loop run: max |L_world| (N·m·s); max |h_wheels + I_r ω| (N·m·s,
    body: the wheels' absolute momenta against the body's); max |φ − φ_ref| (rad) and
    max |ω − φ̇_ref n| (rad/s) against the exact recursion; final attitude error φ(T) of the
    FMU and of the recursion (rad); start angle φ0 (rad); peak wheel rate (rad/s, relative)
    and peak body momentum |I_r ω| (N·m·s), to show the exchange happened."""

    L_max: float
    exchange: float
    dphi: float
    dw: float
    final_error: float
    final_error_ref: float
    phi0: float
    wheel_rate_max: float
    body_momentum_max: float


def slew_run(fmu_path: Path, sc: Scene, stop_time: float | None = None) -> tuple[RunResult, PDSlew]:
    """The FMU's closed-loop slew of `sc` (start at rest, wheels at rest, target the
    identity) and the law that closed it."""
    if np.any(sc.w0 != 0.0) or any(r.Omega0 != 0.0 for r in sc.rotors.values()):
        raise ValueError("the slew check needs a start at rest, wheels at rest (total angular momentum 0)")
    law = slew_law(sc, *SLEW_GAINS)
    return run(fmu_path, sc, stop_time=stop_time, input_fn=law), law


def slew(fmu_path: Path, sc: Scene, stop_time: float | None = None, r: RunResult | None = None) -> Slew:
    """The closed-loop slew of `sc` (`slew_run`, or its result `r`) against the exact recursion."""
    if r is None:
        r = slew_run(fmu_path, sc, stop_time)[0]
    law = slew_law(sc, *SLEW_GAINS)
    q, w = r.vector("q"), r.vector("w_body")
    v0 = np.asarray(sc.q0[1:], dtype=float)
    n_axis = v0 / np.linalg.norm(v0)
    phi0 = 2.0 * math.atan2(float(np.linalg.norm(v0)), float(sc.q0[0]))
    phi = 2.0 * np.arctan2(q[:, 1:] @ n_axis, q[:, 0])  # signed angle about n (q stays about n)
    H = float(np.diff(r.time)[0])
    if np.ptp(np.diff(r.time)) > 1e-12 * r.time[-1]:
        raise ValueError("the recursion needs equal communication steps")
    phi_ref, dphi_ref = eigenaxis_reference(phi0, *SLEW_GAINS, H, len(r.time) - 1)
    h = np.column_stack([r.values[f"h_{n}"] for n in sc.rotors])
    G = law.G
    body = w @ law.I_r.T
    return Slew(
        L_max=float(np.max(np.abs(r.vector("L_world")))),
        exchange=float(np.max(np.abs(h @ G.T + body))),
        dphi=float(np.max(np.abs(phi - phi_ref))),
        dw=float(np.max(np.abs(w - dphi_ref[:, None] * n_axis))),
        final_error=float(2.0 * math.atan2(float(np.linalg.norm(q[-1, 1:])), abs(float(q[-1, 0])))),
        final_error_ref=float(abs(phi_ref[-1])),
        phi0=phi0,
        wheel_rate_max=max(float(np.max(np.abs(r.values[f"Omega_{n}"]))) for n in sc.rotors),
        body_momentum_max=float(np.max(np.linalg.norm(body, axis=1))),
    )


def exudyn_slew(r: RunResult, sc: Scene, h: float) -> Agreement:
    """The FMU's closed-loop run `r` against the jointed Exudyn gyrostat closing the same PD
    loop on its own outputs at the same communication points (u held over each step, as the
    FMU's importer holds it), Richardson from Exudyn's internal steps h and h/2 (s): q,
    w_body (rad/s) and each wheel's Omega (rad/s, relative)."""
    law = slew_law(sc, *SLEW_GAINS)
    T, H = float(r.time[-1]), float(np.diff(r.time)[0])
    coarse, fine = (simulate_gyrostat(sc, stop_time=T, step=H, h=hh, input_fn=law) for hh in (h, h / 2))
    fmu = {"q": r.vector("q"), "w_body": r.vector("w_body")}
    fmu.update({f"Omega_{n}": r.values[f"Omega_{n}"] for n in sc.rotors})
    return richardson_agreement(fmu, coarse, fine, list(fmu))


@scene_check("reaction_wheel_slew", quick_stop_time=40.0)
def reaction_wheel_slew(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """The closed-loop slew (rbcheck.closed_forms.slew) against the exact sampled-data eigenaxis recursion
    and against the same loop around the jointed Exudyn gyrostat."""
    r, _ = slew_run(fmu_path, sc)
    s = slew(fmu_path, sc, r=r)
    h = EXUDYN_STEP[quick]
    ag = exudyn_slew(r, sc, h)
    wheels = [f"Omega_{n}" for n in sc.rotors]
    dw = (ag.diff, ag.estimate)
    start = f"final attitude error (start {math.degrees(s.phi0):.0f} deg)"
    # tolerances (rbcheck.checks.bounds): the loop runs the scene's stop time; the sizes of the
    # motion: the momentum the wheels exchange with the body, the slew angle, the body rate that
    # momentum gives the least inertia, the peak wheel rate
    T, phi0 = sc.stop_time, s.phi0
    h_size = s.body_momentum_max
    w_size = h_size / float(np.min(np.diag(sc.inertia)))
    rows = [
        Row("max|L_world| (0 from rest)", "N m s", s.L_max, NAN, 0.0, allowed(sc, T, h_size)),
        Row("max|h_wheels + I_r w| (wheels vs body)", "N m s", s.exchange, NAN, 0.0, allowed(sc, T, h_size)),
        Row("peak body momentum |I_r w| exchanged", "N m s", s.body_momentum_max, NAN),
        Row("peak wheel rate (relative)", "rad/s", s.wheel_rate_max, NAN),
        Row("max|phi - phi_exact| (slew angle)", "rad", s.dphi, NAN, 0.0, allowed(sc, T, phi0)),
        Row("max|w - dphi_exact n| (eigenaxis)", "rad/s", s.dw, NAN, 0.0, allowed(sc, T, w_size)),
        Row(start, "rad", s.final_error, NAN, s.final_error_ref, allowed(sc, T, phi0)),
        Row("max|q - q_Exudyn| (same loop in Exudyn)", "-", ag.diff["q"], ag.estimate["q"], NAN,
            allowed(sc, T, 1.0, reference=ag.estimate["q"])),
        Row("max|w - w_Exudyn|", "rad/s", ag.diff["w_body"], ag.estimate["w_body"], NAN,
            allowed(sc, T, w_size, reference=ag.estimate["w_body"])),
        Row("max|Omega - Omega_Exudyn| (wheels)", "rad/s", max(dw[0][k] for k in wheels), max(dw[1][k] for k in wheels),
            NAN, allowed(sc, T, s.wheel_rate_max, reference=max(dw[1][k] for k in wheels))),
    ]  # fmt: skip
    note = (
        f"closed loop from fmpy: PD law of rbcheck.closed_forms.slew (k_p {SLEW_GAINS[0]:g} 1/s^2, k_d "
        f"{SLEW_GAINS[1]:g} 1/s), "
        "u held over each communication step; reference: the exact sampled-data eigenaxis recursion "
        "(docs/theory.md §8.4); Exudyn: each wheel on a revolute joint (rbcheck.exudyn.rotors), the same loop on "
        f"its own outputs, Richardson from h = {h:g}, {h / 2:g} s; its column in the Exudyn rows: its own error "
        "estimate |x(h) - x(h/2)|"
    )
    return CheckOutput(rows, note, {"slew": s, "exudyn": ag})
