"""The reaction-wheel slew's check: the closed PD loop from fmpy against its exact sampled-data solution.

Runs the scene ``reaction_wheel_slew`` with the PD law of :mod:`rbcheck.slew` as the
importer's input function (u computed at every communication point from the outputs q and
w_body, held over the step) and compares with the exact eigenaxis recursion there
(docs/theory.md §8.4): total world angular momentum (0 from rest), the wheels' momenta
against the body's, the slew angle and the final attitude error. Units SI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from modelsrc.scene import Scene

from ..slew import eigenaxis_reference, slew_law
from .common import run
from .registry import CheckOutput, Row, scene_check

__all__ = ["SLEW_GAINS", "Slew", "slew"]

NAN = float("nan")
# k_p (1/s²), k_d (1/s) of the slew: ω_n = sqrt(k_p/2) = 0.5 rad/s, critically damped (k_d² = 2 k_p)
SLEW_GAINS = (0.5, 1.0)


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


def slew(fmu_path: Path, sc: Scene, stop_time: float | None = None) -> Slew:
    """The closed-loop slew of `sc` (start at rest, wheels at rest, target the identity)."""
    if np.any(sc.w0 != 0.0) or any(r.Omega0 != 0.0 for r in sc.rotors.values()):
        raise ValueError("the slew check needs a start at rest, wheels at rest (total angular momentum 0)")
    law = slew_law(sc, *SLEW_GAINS)
    r = run(fmu_path, sc, stop_time=stop_time, input_fn=law)
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


@scene_check("reaction_wheel_slew", quick_stop_time=40.0)
def reaction_wheel_slew(fmu_path: Path, sc: Scene, quick: bool) -> CheckOutput:
    """The closed-loop slew (rbcheck.slew) against the exact sampled-data eigenaxis recursion."""
    s = slew(fmu_path, sc)
    start = f"final attitude error (start {math.degrees(s.phi0):.0f} deg)"
    rows = [
        Row("max|L_world| (0 from rest)", "N m s", s.L_max, NAN, 0.0),
        Row("max|h_wheels + I_r w| (wheels vs body)", "N m s", s.exchange, NAN, 0.0),
        Row("peak body momentum |I_r w| exchanged", "N m s", s.body_momentum_max, NAN),
        Row("peak wheel rate (relative)", "rad/s", s.wheel_rate_max, NAN),
        Row("max|phi - phi_exact| (slew angle)", "rad", s.dphi, NAN, 0.0),
        Row("max|w - dphi_exact n| (eigenaxis)", "rad/s", s.dw, NAN, 0.0),
        Row(start, "rad", s.final_error, NAN, s.final_error_ref),
    ]
    note = (
        f"closed loop from fmpy: PD law of rbcheck.slew (k_p {SLEW_GAINS[0]:g} 1/s^2, k_d {SLEW_GAINS[1]:g} 1/s), "
        "u held over each communication step; reference: the exact sampled-data eigenaxis recursion "
        "(docs/theory.md §8.4)"
    )
    return CheckOutput(rows, note, {"slew": s})
